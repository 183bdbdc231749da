//! The gallery: every preset of `stimuli/` rendered with its sidecar and target mask, with
//! thumbnails, a contact sheet and an `index.html` that says what a viewer sees and why.
//!
//! The presets are compiled into the library (so `shadelab gallery` works from any folder);
//! [`load_presets`] reads a folder of specs instead. The output folder is written atomically:
//! it appears complete or not at all. Nothing in it depends on the clock or the thread count,
//! so two runs give identical folders.

use crate::error::{Error, Result};
use crate::grid::{Grid, RgbImage};
use crate::io::{self, BitDepth};
use crate::parallel::prelude::*;
use crate::plot::Caption;
#[cfg(feature = "plots")]
use crate::plot::{caption_pixels, encode, write_rgb_png};
use crate::{self as stimulus, ExportOptions, Output, Pixels, Request, Spec};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// One preset: a file stem and the spec it holds.
#[derive(Debug, Clone, PartialEq)]
pub struct Preset {
    /// The file stem (`bumps` for `stimuli/bumps.json`); names the gallery's files.
    pub name: String,
    /// The spec.
    pub spec: Spec,
    /// Where the spec came from (`stimuli/bumps.json`, or the file read), for errors.
    pub source: PathBuf,
}

/// The presets shipped in `stimuli/`, in gallery order.
pub const BUILTIN: &[(&str, &str)] = &[
    ("bumps", include_str!("../presets/bumps.json")),
    (
        "bumps-gradient",
        include_str!("../presets/bumps-gradient.json"),
    ),
    ("crater", include_str!("../presets/crater.json")),
    (
        "crater-rotated",
        include_str!("../presets/crater-rotated.json"),
    ),
    ("sideways", include_str!("../presets/sideways.json")),
    ("strips", include_str!("../presets/strips.json")),
    (
        "circles-binary",
        include_str!("../presets/circles-binary.json"),
    ),
    (
        "circles-gradient",
        include_str!("../presets/circles-gradient.json"),
    ),
    (
        "circles-odd-one-out",
        include_str!("../presets/circles-odd-one-out.json"),
    ),
    (
        "boundary-strips",
        include_str!("../presets/boundary-strips.json"),
    ),
    (
        "boundary-strips-ramp",
        include_str!("../presets/boundary-strips-ramp.json"),
    ),
    ("hollow-mask", include_str!("../presets/hollow-mask.json")),
    (
        "hollow-mask-convex",
        include_str!("../presets/hollow-mask-convex.json"),
    ),
    (
        "hollow-mask-pair",
        include_str!("../presets/hollow-mask-pair.json"),
    ),
    (
        "checker-shadow",
        include_str!("../presets/checker-shadow.json"),
    ),
    (
        "checker-shadow-proof",
        include_str!("../presets/checker-shadow-proof.json"),
    ),
    ("fading-disk", include_str!("../presets/fading-disk.json")),
    (
        "fading-disk-achromatic",
        include_str!("../presets/fading-disk-achromatic.json"),
    ),
    ("sphere", include_str!("../presets/sphere.json")),
    ("vase", include_str!("../presets/vase.json")),
    ("bunny", include_str!("../presets/bunny.json")),
];

/// The file that marks a folder as a shadelab gallery.
pub const MARKER: &str = "index.html";

/// Where the gallery's index links to the interactive teaching page, relative to the gallery's
/// folder: `web/build.sh GALLERY/teach` builds it there (the gallery itself needs no WebAssembly
/// toolchain, so it does not build the page).
pub const TEACHING_PAGE: &str = "teach/index.html";

/// Longest side of a thumbnail, in pixels.
pub const THUMBNAIL: usize = 256;

/// The display gamma of thumbnails and the contact sheet (the full images stay linear).
pub const THUMBNAIL_GAMMA: f64 = 2.2;

/// The presets compiled into shadelab.
pub fn builtin_presets() -> Result<Vec<Preset>> {
    BUILTIN
        .iter()
        .map(|(name, text)| {
            let spec: Spec = serde_json::from_str(text).map_err(|e| {
                Error::format(
                    format!("stimuli/{name}.json"),
                    format!("bad stimulus spec: {e}"),
                )
            })?;
            Ok(Preset {
                name: name.to_string(),
                spec,
                source: PathBuf::from(format!("stimuli/{name}.json")),
            })
        })
        .collect()
}

/// Every `*.json` spec in `dir`, sorted by file name; hidden files (an editor's `.x.json`,
/// macOS's `._x.json`) are not presets and are passed over.
pub fn load_presets(dir: &Path) -> Result<Vec<Preset>> {
    let entries = std::fs::read_dir(dir).map_err(|e| Error::io(dir, e))?;
    let hidden = |p: &Path| {
        p.file_name()
            .is_some_and(|n| n.to_string_lossy().starts_with('.'))
    };
    let mut paths: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| io::extension(p) == "json" && !hidden(p))
        .collect();
    paths.sort();
    if paths.is_empty() {
        return Err(Error::format(dir, "holds no stimulus specs (*.json)"));
    }
    paths
        .iter()
        .map(|p| {
            let name = p
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            let ok = !name.is_empty()
                && name
                    .chars()
                    .all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_');
            if !ok {
                return Err(Error::format(
                    p,
                    "preset names may hold only letters, digits, '-' and '_'",
                ));
            }
            Ok(Preset {
                name,
                spec: Spec::load(p)?,
                source: p.clone(),
            })
        })
        .collect()
}

/// The docs pages compiled into shadelab, whose sections the gallery's cards carry with them
/// (see [`explanation`]): every page a built-in preset's `docs` names.
const DOCS: &[(&str, &str)] = &[
    ("docs/priors.md", include_str!("../docs/priors.md")),
    ("docs/lightness.md", include_str!("../docs/lightness.md")),
    (
        "docs/ikeuchi-horn.md",
        include_str!("../docs/ikeuchi-horn.md"),
    ),
    ("docs/problem.md", include_str!("../docs/problem.md")),
];

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || matches!(c, ' ' | '-' | '_'))
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The explanation a preset's `docs` link (`docs/priors.md#light-from-above`) points to, from
/// the docs compiled into shadelab: the section's heading and its prose paragraphs up to the
/// next heading (figures, their captions, tables and code left out; links reduced to their
/// text), as plain text. `None` for a page or section shadelab does not carry.
pub fn explanation(docs: &str) -> Option<(String, Vec<String>)> {
    let (page, anchor) = docs.split_once('#')?;
    let text = DOCS.iter().find(|(p, _)| *p == page)?.1;
    let mut lines = text.lines();
    let heading = lines.by_ref().find_map(|l| {
        let title = l.trim_start_matches('#');
        (l.starts_with('#') && title.starts_with(' ') && slug(title) == anchor)
            .then(|| title.trim().to_string())
    })?;
    let mut paragraphs = Vec::new();
    let mut current = String::new();
    let (mut fenced, mut caption) = (false, false);
    for line in lines {
        let t = line.trim();
        if t.starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        if t.starts_with('#') {
            break;
        }
        // A figure's caption: an emphasised paragraph, over one line or several.
        if caption {
            caption = !(t.is_empty() || t.ends_with('*'));
            continue;
        }
        if t.is_empty() || t.starts_with('!') || t.starts_with('|') {
            if !current.is_empty() {
                paragraphs.push(plain(&std::mem::take(&mut current)));
            }
            continue;
        }
        if current.is_empty() && t.starts_with('*') {
            caption = !(t.len() > 1 && t.ends_with('*'));
            continue;
        }
        if !current.is_empty() {
            current.push(' ');
        }
        current.push_str(t);
    }
    if !current.is_empty() {
        paragraphs.push(plain(&current));
    }
    Some((heading, paragraphs))
}

/// Markdown's links reduced to their text (`[a](b)` to `a`) and its emphasis and code marks
/// dropped.
fn plain(markdown: &str) -> String {
    let mut out = String::new();
    let mut rest = markdown;
    while let Some(open) = rest.find('[') {
        let tail = &rest[open..];
        match tail
            .find("](")
            .and_then(|mid| tail[mid..].find(')').map(|close| (mid, mid + close)))
        {
            Some((mid, close)) => {
                out.push_str(&rest[..open]);
                out.push_str(&tail[1..mid]);
                rest = &tail[close + 1..];
            }
            None => {
                out.push_str(&rest[..=open]);
                rest = &rest[open + 1..];
            }
        }
    }
    out.push_str(rest);
    out.replace(['*', '`'], "")
}

/// How to build a gallery.
#[derive(Debug, Clone, PartialEq)]
pub struct Options {
    /// Largest image made, in pixels.
    pub max_pixels: usize,
    /// Links from each picture to its explanation in shadelab's docs: the prefix put before the
    /// preset's `docs` path (`docs/priors.md#…`, relative to the repository root), e.g. a URL
    /// of the repository's files, or `../` for a gallery one level below a checkout. `None`
    /// (the default): no link leaves the gallery's folder; each card carries its explanation.
    pub docs_base: Option<String>,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            max_pixels: crate::grid::DEFAULT_MAX_PIXELS,
            docs_base: None,
        }
    }
}

/// What was rendered for one preset, in memory until [`write_into`] writes it.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// The preset.
    pub preset: Preset,
    /// The resolved request (parameters, size, seed).
    pub request: Request,
    /// The picture and its targets.
    pub output: Output,
    thumbnail: RgbImage,
}

impl Rendered {
    /// The names of the files written for it in the gallery folder (image, mask, sidecar).
    pub fn files(&self) -> Vec<String> {
        // In the order `write_output` lists them: companions, image, sidecar.
        let image = PathBuf::from(format!("{}.png", self.preset.name));
        let mut files = stimulus::planned_files(&image, &self.output, &ExportOptions::default());
        files.rotate_left(1);
        files.push(io::sibling(&image, "", "json"));
        files
            .iter()
            .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
            .collect()
    }
}

/// Checks that there is at least one preset and that no two share a name (their files would).
pub fn check_presets(presets: &[Preset]) -> Result<()> {
    if presets.is_empty() {
        return Err(Error::invalid("the gallery needs at least one preset"));
    }
    let mut seen = std::collections::BTreeSet::new();
    for p in presets {
        if !seen.insert(p.name.as_str()) {
            return Err(Error::invalid(format!(
                "two presets are called '{}'",
                p.name
            )));
        }
    }
    Ok(())
}

/// Renders every preset (in parallel), in memory. `progress` is called with each preset's
/// name when it is done (from worker threads).
pub fn render(
    presets: &[Preset],
    options: &Options,
    progress: &(dyn Fn(&str) + Sync),
) -> Result<Vec<Rendered>> {
    check_presets(presets)?;
    presets
        .par_iter()
        .map(|preset| {
            let r = render_one(preset, options);
            progress(&preset.name);
            r
        })
        .collect()
}

/// Writes the gallery of `rendered` into the folder `dir`: per preset `NAME.png` (16-bit
/// linear), `NAME.json`, `NAME_mask.png` where it has targets, `thumbs/NAME.png`; then
/// `gallery.png` (all thumbnails) and `index.html` ([`MARKER`]), whose links to the
/// explanations start with `docs_base` (none without one), and which links the teaching page
/// only when `teach` (it lies in the gallery's folder, [`TEACHING_PAGE`]).
pub fn write_into(
    dir: &Path,
    rendered: &[Rendered],
    docs_base: Option<&str>,
    teach: bool,
) -> Result<()> {
    let thumbs = dir.join("thumbs");
    std::fs::create_dir(&thumbs).map_err(|e| Error::io(&thumbs, e))?;
    rendered
        .par_iter()
        .map(|r| write_one(r, dir))
        .collect::<Result<Vec<()>>>()?;
    write_sheet(&dir.join("gallery.png"), rendered)?;
    let html = index_html(rendered, docs_base, teach);
    io::write_text(&dir.join(MARKER), &html)
}

fn render_one(preset: &Preset, options: &Options) -> Result<Rendered> {
    // Workers stop at a requested stop; the caller drops what was rendered.
    crate::cancel::check()?;
    let spec = &preset.spec;
    let context = |e: Error| match e {
        Error::TooLarge(m) => Error::TooLarge(format!("{}: {m}", preset.source.display())),
        other => Error::format(&preset.source, other.to_string()),
    };
    let (request, output) = stimulus::generate(
        &spec.stimulus,
        &spec.params,
        &spec.size(),
        spec.seed.unwrap_or(0),
        options.max_pixels,
    )
    .map_err(context)?;
    let thumbnail = thumbnail(&output);
    Ok(Rendered {
        preset: preset.clone(),
        request,
        output,
        thumbnail,
    })
}

fn write_one(r: &Rendered, dir: &Path) -> Result<()> {
    crate::cancel::check()?;
    let name = &r.preset.name;
    stimulus::write_output(
        &r.preset.spec.stimulus,
        &r.request,
        &r.output,
        &dir.join(format!("{name}.png")),
        // 16-bit linear PNG with its sidecar and mask, into the gallery's own fresh folder.
        &ExportOptions::default(),
        true,
        None,
    )?;
    io::write_rgb(
        &dir.join("thumbs").join(format!("{name}.png")),
        &r.thumbnail,
        BitDepth::Eight,
        Some(THUMBNAIL_GAMMA),
    )
}

/// A box-filtered reduction to at most [`THUMBNAIL`] pixels on the longer side (linear RGB).
fn thumbnail(output: &Output) -> RgbImage {
    let rgb: RgbImage = match &output.pixels {
        Pixels::Gray(g) => g.map(|&v| [v; 3]),
        Pixels::Rgb(c) => c.clone(),
    };
    let (w, h) = (rgb.width(), rgb.height());
    let factor = w.max(h).div_ceil(THUMBNAIL).max(1);
    let (tw, th) = (w.div_ceil(factor), h.div_ceil(factor));
    Grid::from_fn(tw, th, |c, r| {
        let mut acc = [0.0; 3];
        let mut n = 0.0;
        for y in r * factor..((r + 1) * factor).min(h) {
            for x in c * factor..((c + 1) * factor).min(w) {
                let p = rgb.get(x, y);
                for k in 0..3 {
                    acc[k] += p[k];
                }
                n += 1.0;
            }
        }
        acc.map(|a| a / n)
    })
}

/// Height of the caption band under each thumbnail on the contact sheet, in pixels.
const CAPTION: usize = 44;

/// All thumbnails on one sheet, four to a row, each centred in its cell above a band for its
/// caption.
fn contact_sheet(rendered: &[Rendered]) -> RgbImage {
    let (cols, gap) = (4usize, 12usize);
    let rows = rendered.len().div_ceil(cols);
    let (cell_w, cell_h) = (THUMBNAIL + gap, THUMBNAIL + CAPTION + gap);
    let mut sheet = Grid::new(cols * cell_w + gap, rows * cell_h + gap, [1.0; 3]);
    for (i, r) in rendered.iter().enumerate() {
        let t = &r.thumbnail;
        let x0 = gap + (i % cols) * cell_w + (THUMBNAIL - t.width()) / 2;
        let y0 = gap + (i / cols) * cell_h + (THUMBNAIL - t.height()) / 2;
        for y in 0..t.height() {
            for x in 0..t.width() {
                *sheet.get_mut(x0 + x, y0 + y) = *t.get(x, y);
            }
        }
    }
    sheet
}

/// The captions of the contact sheet: under each thumbnail its preset's name and, on a second
/// line, its title (or the stimulus's name).
fn sheet_captions(rendered: &[Rendered]) -> Vec<Caption> {
    let (cols, gap) = (4usize, 12usize);
    let (cell_w, cell_h) = (THUMBNAIL + gap, THUMBNAIL + CAPTION + gap);
    rendered
        .iter()
        .enumerate()
        .flat_map(|(i, r)| {
            let x = (gap + (i % cols) * cell_w + THUMBNAIL / 2) as i32;
            let y = (gap + (i / cols) * cell_h + THUMBNAIL + 4) as i32;
            let line = r
                .preset
                .spec
                .title
                .clone()
                .unwrap_or_else(|| r.preset.spec.stimulus.clone());
            [
                Caption {
                    at: (x, y),
                    text: r.preset.name.clone(),
                    size: 16.0,
                    width: THUMBNAIL as u32,
                },
                Caption {
                    at: (x, y + 20),
                    text: line,
                    size: 13.0,
                    width: THUMBNAIL as u32,
                },
            ]
        })
        .collect()
}

/// Writes the contact sheet, display-encoded, with its captions where plots are built in.
fn write_sheet(path: &Path, rendered: &[Rendered]) -> Result<()> {
    let sheet = contact_sheet(rendered);
    #[cfg(feature = "plots")]
    {
        let size = (sheet.width() as u32, sheet.height() as u32);
        let mut bytes: Vec<u8> = sheet
            .data()
            .iter()
            .flat_map(|p| p.map(|v| encode(v, Some(THUMBNAIL_GAMMA))))
            .collect();
        caption_pixels(&mut bytes, size, &sheet_captions(rendered))?;
        write_rgb_png(path, &bytes, size)
    }
    #[cfg(not(feature = "plots"))]
    {
        let _ = sheet_captions;
        io::write_rgb(path, &sheet, BitDepth::Eight, Some(THUMBNAIL_GAMMA))
    }
}

fn escape(text: &str) -> String {
    text.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// The link from the gallery to a preset's explanation: `base` then the preset's `docs` path.
/// A base without a trailing slash gets one, so `https://host/repo/blob/main` works too.
pub fn docs_link(base: &str, docs: &str) -> String {
    if base.is_empty() || base.ends_with('/') {
        format!("{base}{docs}")
    } else {
        format!("{base}/{docs}")
    }
}

fn index_html(rendered: &[Rendered], docs_base: Option<&str>, teach: bool) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        r#"<!DOCTYPE html>
<html lang="en">
<head>
<meta charset="utf-8">
<title>shadelab gallery</title>
<style>
body {{ font-family: sans-serif; max-width: 1100px; margin: 2em auto; color: #222; }}
.card {{ display: flex; gap: 1.5em; margin: 2em 0; border-top: 1px solid #ccc; padding-top: 1.5em; }}
.card img {{ max-width: {THUMBNAIL}px; image-rendering: auto; }}
.explained {{ font-size: 0.92em; color: #333; }}
table {{ border-collapse: collapse; font-size: 0.85em; }}
td {{ padding: 0 0.8em 0 0; vertical-align: top; }}
code {{ background: #f3f3f3; padding: 0 0.2em; }}
</style>
</head>
<body>
<h1>shadelab gallery</h1>
<p>Every picture below is a preset from <code>stimuli/</code>, rendered by shadelab {version}.
Full images (click a thumbnail) are 16-bit PNGs of <em>linear</em> luminance 0..1, for a calibrated
(linearised) display; thumbnails are display-encoded with gamma {gamma} so they look right on an
ordinary screen. Beside each image lie its JSON sidecar (every parameter, the seed, an md5) and
its target mask (<code>_mask.png</code>: 0 = background, 1..N = the named targets).
{explained}</p>
<p>{teach}</p>
"#,
        version = io::PROGRAM_VERSION,
        gamma = THUMBNAIL_GAMMA,
        explained = match docs_base {
            Some(_) => "Each picture links to the page of shadelab's documentation that explains it.",
            None => "Each picture comes with the explanation from shadelab's documentation; this \
                folder stands alone (copy it anywhere; <code>shadelab gallery --docs-base URL</code> \
                also links each picture to its page).",
        },
        teach = if teach {
            format!(
                "Move the light yourself: the <a href=\"{TEACHING_PAGE}\">interactive teaching \
                 page</a> renders these stimuli and runs shadelab's shape-from-shading engine \
                 live in the browser (WebAssembly)."
            )
        } else {
            "An interactive teaching page (move the light, run shadelab's shape-from-shading \
             engine live in the browser) can go into this folder: build it with \
             <code>web/build.sh GALLERY/teach</code> (see shadelab's docs/teaching.md), then \
             run <code>shadelab gallery</code> again to link it here."
                .to_string()
        },
    );
    for r in rendered {
        let p = &r.preset;
        let g = &r.request.geometry;
        let title = p.spec.title.clone().unwrap_or_else(|| p.name.clone());
        let caption = p.spec.caption.clone().unwrap_or_default();
        let _ = write!(
            h,
            r#"<div class="card" id="{id}">
<a href="{id}.png"><img src="thumbs/{id}.png" alt="{alt}"></a>
<div>
<h2>{title}</h2>
<p>{caption}</p>
{explained}<p>Stimulus <code>{stimulus}</code>, {wd:.2}&times;{hd:.2}&deg; at {ppd} pixels per degree = {w}&times;{h} pixels, seed {seed}.
Reproduce: <code>shadelab render --spec stimuli/{id}.json --out {id}.png</code></p>
<table>
"#,
            id = escape(&p.name),
            alt = escape(&title),
            title = escape(&title),
            caption = escape(&caption),
            explained = match (&p.spec.docs, docs_base) {
                (Some(d), Some(base)) => format!(
                    "<p class=\"explained\">Explained in <a href=\"{href}\">{text}</a>.</p>\n",
                    href = escape(&docs_link(base, d)),
                    text = escape(d),
                ),
                (Some(d), None) => match explanation(d) {
                    Some((heading, paragraphs)) => format!(
                        "<div class=\"explained\"><h3>{heading}</h3>\n{body}\n<p>From shadelab's {page}.</p></div>\n",
                        heading = escape(&heading),
                        body = paragraphs
                            .iter()
                            .map(|t| format!("<p>{}</p>", escape(t)))
                            .collect::<Vec<_>>()
                            .join("\n"),
                        page = escape(d.split('#').next().unwrap_or(d)),
                    ),
                    None => format!(
                        "<p class=\"explained\">Explained in shadelab's {}.</p>\n",
                        escape(d)
                    ),
                },
                (None, _) => String::new(),
            },
            stimulus = escape(&p.spec.stimulus),
            wd = g.width_deg(),
            hd = g.height_deg(),
            ppd = g.ppd,
            w = g.width,
            h = g.height,
            seed = r.request.seed,
        );
        if let serde_json::Value::Object(params) = r.request.params.to_json() {
            for (k, v) in params {
                let v = match v {
                    serde_json::Value::String(s) => s,
                    other => other.to_string(),
                };
                let _ = writeln!(
                    h,
                    "<tr><td><code>{}</code></td><td>{}</td></tr>",
                    escape(&k),
                    escape(&v)
                );
            }
        }
        let links: Vec<String> = r
            .files()
            .iter()
            .map(|f| format!("<a href=\"{0}\">{0}</a>", escape(f)))
            .collect();
        let _ = write!(
            h,
            "</table>\n<p>Files: {}</p>\n</div>\n</div>\n",
            links.join(", ")
        );
    }
    h.push_str("</body>\n</html>\n");
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_builtin_preset_parses_and_names_a_stimulus() {
        let presets = builtin_presets().unwrap();
        assert_eq!(presets.len(), BUILTIN.len());
        let names = stimulus::names();
        for p in &presets {
            assert!(names.contains(&p.spec.stimulus.as_str()), "{}", p.name);
            assert!(
                p.spec.title.is_some() && p.spec.caption.is_some() && p.spec.docs.is_some(),
                "{}",
                p.name
            );
        }
    }

    #[test]
    fn thumbnails_average_and_fit() {
        // 700 wide needs a factor of 3 to fit 256: columns 0, 1, 0 average to 1/3.
        let mut out = crate::Output::gray(Grid::from_fn(700, 100, |c, _| (c % 2) as f64));
        let t = thumbnail(&out);
        assert_eq!((t.width(), t.height()), (234, 34));
        let v = t.get(0, 0)[0];
        assert!((v - 1.0 / 3.0).abs() < 1e-12, "{v}");
        out.pixels = Pixels::Gray(Grid::new(10, 10, 0.5));
        assert_eq!(thumbnail(&out).width(), 10);
        assert!(escape("<a & \"b\">").contains("&lt;a &amp; &quot;b&quot;&gt;"));
    }

    #[test]
    fn hidden_files_are_not_presets() {
        let dir = std::env::temp_dir().join(format!("shadelab-presets-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("disc.json"), r#"{"stimulus": "disc"}"#).unwrap();
        std::fs::write(dir.join("._disc.json"), [0u8, 5, 22, 7]).unwrap();
        std::fs::write(dir.join(".#disc.json"), "not json").unwrap();
        let presets = load_presets(&dir);
        std::fs::remove_dir_all(&dir).unwrap();
        let names: Vec<String> = presets.unwrap().into_iter().map(|p| p.name).collect();
        assert_eq!(names, ["disc"]);
    }

    #[test]
    fn the_index_links_to_the_teaching_page_only_when_it_is_there() {
        let html = index_html(&[], None, true);
        assert!(html.contains("<a href=\"teach/index.html\">interactive teaching"));
        let html = index_html(&[], None, false);
        assert!(!html.contains("href") && html.contains("web/build.sh GALLERY/teach"));
    }

    #[test]
    fn every_builtin_presets_explanation_travels_with_it() {
        for p in builtin_presets().unwrap() {
            let docs = p.spec.docs.clone().unwrap();
            let (heading, paragraphs) =
                explanation(&docs).unwrap_or_else(|| panic!("{}: {docs} not carried", p.name));
            assert!(!heading.is_empty(), "{docs}");
            let text = paragraphs.join(" ");
            assert!(text.len() > 100, "{docs}: {text}");
            assert!(
                !text.contains("](") && !text.contains("images/"),
                "{docs}: {text}"
            );
        }
        let (heading, paragraphs) = explanation("docs/priors.md#light-from-above").unwrap();
        assert_eq!(heading, "Light from above");
        assert!(
            paragraphs[0].starts_with("Discs bright on top look like bumps"),
            "{paragraphs:?}"
        );
        assert!(explanation("docs/priors.md#no-such-section").is_none());
        assert_eq!(
            plain("see [the page](a.md#b) and `code`"),
            "see the page and code"
        );
    }

    #[test]
    fn docs_links_join_base_and_page_with_one_slash() {
        assert_eq!(docs_link("../", "docs/a.md#b"), "../docs/a.md#b");
        assert_eq!(docs_link("", "docs/a.md"), "docs/a.md");
        assert_eq!(
            docs_link("https://x.org/r/blob/main", "docs/a.md#b"),
            "https://x.org/r/blob/main/docs/a.md#b"
        );
    }
}
