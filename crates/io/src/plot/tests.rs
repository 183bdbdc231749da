use super::axes::{tick_text, ticks};
use super::*;
use crate::colormap::Colormap;
use crate::grid::Grid;

fn cosine(name: &str, phase: f64) -> Series {
    Series {
        name: name.into(),
        points: (0..12)
            .map(|i| {
                let t = i as f64 * 30.0;
                (t, (t + phase).to_radians().cos())
            })
            .collect(),
    }
}

#[test]
fn a_plot_draws_its_curve_in_colour_and_text_in_svg() {
    let mut plot = LinePlot::new("test", "tilt (°)", "convexity", (0.0, 360.0));
    plot.reference_y = Some(0.0);
    plot.series.push(cosine("disc", 0.0));
    plot.size = (320, 200);
    let (rgb, _) = plot.rgb().unwrap();
    assert_eq!(rgb.len(), 320 * 200 * 3);
    // The curve's blue is there, and text was drawn (dark pixels beside white).
    let blue = rgb.chunks_exact(3).filter(|p| p == &[0, 114, 178]).count();
    assert!(blue > 100, "{blue}");
    let dark = rgb
        .chunks_exact(3)
        .filter(|p| p.iter().all(|&v| v < 80))
        .count();
    assert!(dark > 50, "{dark}");
    let svg = plot.svg().unwrap();
    assert!(svg.contains("<svg") && svg.contains("convexity"));
}

#[test]
fn a_circle_closes_and_its_axis_ends_at_360() {
    let mut plot = LinePlot::new("t", "assumed tilt (°)", "convexity", (0.0, 330.0));
    plot.series.push(cosine("a", 0.0));
    plot.series.push(cosine("b", 90.0));
    assert!(plot.close_circle());
    assert_eq!(
        plot.series[1].points[12],
        (360.0, plot.series[1].points[0].1)
    );
    let texts = svg_texts(&plot.svg().unwrap());
    assert_eq!(
        texts
            .iter()
            .filter(|t| t.parse::<f64>().is_ok())
            .max_by(|a, b| {
                a.parse::<f64>()
                    .unwrap()
                    .total_cmp(&b.parse::<f64>().unwrap())
            }),
        Some(&"360".to_string()),
        "the last tick is 360"
    );
    assert!(texts.contains(&"0".into()) && texts.contains(&"90".into()));
    // Not a circle: left alone.
    let mut open = LinePlot::new("t", "x", "y", (0.0, 90.0));
    open.series.push(Series {
        name: "a".into(),
        points: vec![(0.0, 1.0), (90.0, 2.0)],
    });
    assert!(!open.close_circle());
    assert_eq!(open.series[0].points.len(), 2);
}

#[test]
fn integer_ticks_are_whole_numbers() {
    let mut plot = LinePlot::new("conv", "cycle (count)", "y", (1.0, 4.0));
    plot.x_ticks = Ticks::Integer;
    plot.series.push(Series {
        name: "a".into(),
        points: vec![(1.0, 1.0), (2.0, 0.5), (3.0, 0.2), (4.0, 0.1)],
    });
    let texts = svg_texts(&plot.svg().unwrap());
    assert!(
        texts.contains(&"2".into()) && texts.contains(&"4".into()),
        "{texts:?}"
    );
    assert!(!texts.contains(&"2.0".into()) && !texts.contains(&"1.5".into()));
    let (t, d) = ticks(1.0, 3.0, Ticks::Integer);
    assert_eq!((t, d), (vec![1.0, 2.0, 3.0], 0));
}

#[test]
fn many_curves_are_grouped_by_class_in_a_legend_beside_the_data() {
    let mut plot = LinePlot::new("many", "tilt (°)", "convexity", (0.0, 330.0));
    for i in 0..24 {
        let kind = if i % 2 == 0 { "bump" } else { "dimple" };
        let phase = if i % 2 == 0 { 0.0 } else { 180.0 };
        plot.series
            .push(cosine(&format!("{kind} r{}c{}", i / 6, i % 6), phase));
    }
    let (colours, entries) = plot.legend();
    assert_eq!(
        entries,
        vec![
            ("bumps (n=12)".to_string(), 0),
            ("dimples (n=12)".to_string(), 1)
        ]
    );
    assert!(colours.iter().enumerate().all(|(i, &c)| c == i % 2));
    let texts = svg_texts(&plot.svg().unwrap());
    assert!(texts.contains(&"bumps (n=12)".into()) && texts.contains(&"dimples (n=12)".into()));
    // The legend's swatches (3 px lines of the class colours) lie right of the data area.
    let (rgb, (cols, rows)) = plot.rgb().unwrap();
    let (w, _) = plot.size;
    let orange = [213u8, 94, 0];
    let mut in_data = 0;
    let mut right = 0;
    for (i, p) in rgb.chunks_exact(3).enumerate() {
        if p == orange {
            let x = (i % w as usize) as i32;
            if x >= cols.end + 4 {
                right += 1;
            } else if cols.contains(&x) {
                in_data += 1;
            }
        }
    }
    assert!(right > 40, "a swatch right of the data area: {right}");
    assert!(in_data > 100, "the dimples' curves: {in_data}");
    // The legend box's border does not reach into the data area.
    let grey: Vec<(i32, i32)> = rgb
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| *p == [160, 160, 160])
        .map(|(i, _)| ((i % w as usize) as i32, (i / w as usize) as i32))
        .collect();
    assert!(grey.iter().any(|&(x, _)| x >= cols.end), "a legend box");
    assert!(
        !grey
            .iter()
            .any(|&(x, y)| cols.contains(&x) && rows.contains(&y)),
        "the legend box is drawn in the data area"
    );
}

/// The text of every `<text>` element of an SVG, trimmed.
fn svg_texts(svg: &str) -> Vec<String> {
    svg.split("</text>")
        .filter_map(|part| part.rsplit_once('>').map(|(_, t)| t.trim().to_string()))
        .filter(|t| !t.is_empty())
        .collect()
}

#[test]
fn tick_labels_have_enough_decimals_and_no_negative_zero() {
    let (_, d) = ticks(0.0, 360.0, Ticks::Auto);
    assert_eq!(tick_text(90.0, d), "90");
    let (t, d) = ticks(-0.15, 0.15, Ticks::Auto);
    assert_eq!(tick_text(-0.0, d), "0.00");
    assert_eq!(tick_text(-0.000001, d), "0.00");
    assert!(t.iter().any(|v| tick_text(*v, d) == "0.10"), "{t:?}");
}

#[test]
fn a_map_has_a_colour_bar_from_the_maps_start_to_its_end_and_outlines() {
    let values = Grid::from_fn(40, 20, |c, _| c as f64 / 39.0);
    let picture = Colormap::Viridis.paint(&values, (0.0, 1.0), None, [1.0; 3]);
    let bar = ColourBar {
        colormap: Colormap::Viridis,
        range: (0.0, 1.0),
        label: "R (linear luminance)".into(),
    };
    let mut fig = MapFigure::new("map", picture, bar);
    fig.outlines.push(Outline {
        mask: Grid::from_fn(40, 20, |c, r| (10..20).contains(&c) && (5..15).contains(&r)),
        name: "A".into(),
    });
    fig.size = (600, 400);
    let (rgb, map, bar) = fig.rgb().unwrap();
    let at = |x: i32, y: i32| {
        let i = (y as usize * 600 + x as usize) * 3;
        [rgb[i], rgb[i + 1], rgb[i + 2]]
    };
    let code = |t: f64| Colormap::Viridis.linear(t).map(|v| encode(v, Some(2.2)));
    let mid = (bar.0.start + bar.0.end) / 2;
    assert_eq!(at(mid, bar.1.start), code(1.0), "top of the bar");
    assert_eq!(at(mid, bar.1.end - 1), code(0.0), "bottom of the bar");
    // The map keeps the picture's aspect (2:1) and shows its left and right ends.
    let (mw, mh) = (map.0.end - map.0.start, map.1.end - map.1.start);
    assert!((mw - 2 * mh).abs() <= 2, "{mw} x {mh}");
    assert_eq!(at(map.0.start, map.1.end - 1), code(0.0));
    assert_eq!(at(map.0.end - 1, map.1.end - 1), code(1.0));
    // The outline is red around the region (its left edge at column 10 of 40).
    // The first figure column showing picture column 10.
    let x = map.0.start + (10 * mw + 39) / 40;
    let y = map.1.start + (10 * mh) / 20;
    assert_eq!(at(x, y), OUTLINE);
    assert_ne!(at(x + 6, y), OUTLINE, "inside the region is the map");
}

#[test]
fn captions_are_drawn_and_cut_to_their_width() {
    let (w, h) = (200u32, 40u32);
    let mut buf = vec![255u8; (w * h * 3) as usize];
    caption_pixels(
        &mut buf,
        (w, h),
        &[Caption {
            at: (100, 4),
            text: "a caption far too long to fit in the narrow cell it is given".into(),
            size: 14.0,
            width: 120,
        }],
    )
    .unwrap();
    let dark: Vec<usize> = buf
        .chunks_exact(3)
        .enumerate()
        .filter(|(_, p)| p[0] < 128)
        .map(|(i, _)| i % w as usize)
        .collect();
    assert!(dark.len() > 50);
    assert!(
        dark.iter().all(|&x| (38..=162).contains(&x)),
        "cut to 120 px"
    );
}
