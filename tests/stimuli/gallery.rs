//! The gallery: every preset rendered with captions and files.

use super::*;
use crate::cli::{assert_error, scratch, shadelab};
use std::collections::BTreeSet;
use std::path::Path;

#[test]
fn the_gallery_renders_every_preset_with_captions_and_files() {
    let d = scratch("stim-gallery");
    let out = shadelab(&d, &["gallery", "--out", "g"]);
    ok(&out);
    let g = d.join("g");
    let html = std::fs::read_to_string(g.join("index.html")).unwrap();
    let presets = shadelab_stimuli::gallery::builtin_presets().unwrap();
    // Every spec in stimuli/ is a built-in preset.
    let on_disk: BTreeSet<String> =
        std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("stimuli"))
            .unwrap()
            .map(|e| e.unwrap().path())
            .filter(|p| p.extension().is_some_and(|e| e == "json"))
            .map(|p| p.file_stem().unwrap().to_string_lossy().into_owned())
            .collect();
    let built_in: BTreeSet<String> = presets.iter().map(|p| p.name.clone()).collect();
    assert_eq!(on_disk, built_in);
    for p in &presets {
        let title = p.spec.title.as_deref().unwrap();
        assert!(
            html.contains(&title.replace('&', "&amp;")),
            "{title} not in index.html"
        );
        for f in [
            format!("{}.png", p.name),
            format!("{}.json", p.name),
            format!("thumbs/{}.png", p.name),
        ] {
            assert!(g.join(&f).exists(), "{f}");
        }
        let meta = sidecar(&g.join(format!("{}.json", p.name)));
        assert_eq!(meta["stimulus"], p.spec.stimulus.as_str());
    }
    assert!(g.join("gallery.png").exists());
    // A second run replaces its own folder and gives the same files.
    let first = std::fs::read(g.join("checker-shadow.png")).unwrap();
    let first_html = html.clone();
    ok(&shadelab(&d, &["gallery", "--out", "g"]));
    assert_eq!(first, std::fs::read(g.join("checker-shadow.png")).unwrap());
    assert_eq!(
        first_html,
        std::fs::read_to_string(g.join("index.html")).unwrap()
    );
    // A folder of someone else's is not replaced.
    std::fs::create_dir(d.join("photos")).unwrap();
    std::fs::write(d.join("photos/holiday.jpg"), "x").unwrap();
    assert_error(&shadelab(&d, &["gallery", "--out", "photos"]), 1, "--force");
    // A custom preset folder works too.
    std::fs::create_dir(d.join("mine")).unwrap();
    std::fs::write(
        d.join("mine/a.json"),
        r#"{"stimulus": "disc", "shape": [32, 32]}"#,
    )
    .unwrap();
    ok(&shadelab(
        &d,
        &["gallery", "--presets", "mine", "--out", "m"],
    ));
    assert!(d.join("m/a.png").exists() && d.join("m/index.html").exists());
}
