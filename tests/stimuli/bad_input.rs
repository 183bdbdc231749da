//! Bad input: one line on stderr, a nonzero exit and nothing written.

use crate::cli::{assert_error, scratch, shadelab};

#[test]
fn bad_input_is_one_line_nonzero_and_writes_nothing() {
    let d = scratch("stim-bad");
    std::fs::write(
        d.join("extra.json"),
        r#"{"stimulus": "bumps", "params": {}, "colour": "red"}"#,
    )
    .unwrap();
    std::fs::write(
        d.join("badparam.json"),
        r#"{"stimulus": "strips", "params": {"width": 2}}"#,
    )
    .unwrap();
    let cases: &[(&[&str], i32, &str)] = &[
        (&["render", "bumpz", "--out", "x.png"], 2, "checker-shadow"),
        (
            &["render", "bumps", "--set", "colour=red", "--out", "x.png"],
            2,
            "valid: profile, radius",
        ),
        (
            &["render", "bumps", "--set", "radius=-1", "--out", "x.png"],
            2,
            "radius",
        ),
        (
            &["render", "bumps", "--set", "radius=0", "--out", "x.png"],
            2,
            "radius",
        ),
        (
            &[
                "render",
                "strips",
                "--set",
                "contrast=1.5",
                "--out",
                "x.png",
            ],
            2,
            "contrast",
        ),
        (
            &[
                "render",
                "circles-binary",
                "--set",
                "contrast=-0.1",
                "--out",
                "x.png",
            ],
            2,
            "contrast",
        ),
        (
            &["render", "checker-shadow", "--ppd", "0", "--out", "x.png"],
            2,
            "ppd",
        ),
        (
            &[
                "render",
                "checker-shadow",
                "--visual-size=-3",
                "--out",
                "x.png",
            ],
            2,
            "positive",
        ),
        (
            &["render", "disc", "--visual-size", "0x4", "--out", "x.png"],
            2,
            "positive",
        ),
        (
            &["render", "fading-disk", "--size", "0x10", "--out", "x.png"],
            2,
            "--size '0x10': both sides must be positive",
        ),
        (
            &[
                "render",
                "crater",
                "--visual-size",
                "8",
                "--ppd",
                "32",
                "--size",
                "300",
                "--out",
                "x.png",
            ],
            2,
            "inconsistent",
        ),
        (
            &["render", "--spec", "extra.json", "--out", "x.png"],
            1,
            "unknown field `colour`",
        ),
        (
            &["render", "--spec", "badparam.json", "--out", "x.png"],
            2,
            "unknown parameter 'width'",
        ),
        (
            &[
                "render",
                "boundary-strips",
                "--set",
                "boundary=wavy",
                "--out",
                "x.png",
            ],
            2,
            "'wavy'",
        ),
        (
            &[
                "render",
                "fading-disk",
                "--set",
                "disk_colour=blue",
                "--out",
                "x.png",
            ],
            2,
            "disk_colour",
        ),
        (
            &["render", "bumps", "--set", "rows=30", "--out", "x.png"],
            2,
            "enlarge",
        ),
        (
            &["render", "strips", "--range", "psychopy", "--out", "x.svg"],
            2,
            "psychopy",
        ),
        (
            &["render", "strips", "--gamma", "2.2", "--out", "x.mat"],
            2,
            "gamma",
        ),
        (
            &["gallery", "--presets", "missing", "--out", "g"],
            1,
            "missing",
        ),
    ];
    for (args, code, needle) in cases {
        let out = shadelab(&d, args);
        assert_error(&out, *code, needle);
    }
    let mut left: Vec<String> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    left.sort();
    assert_eq!(
        left,
        ["badparam.json", "extra.json"],
        "nothing else written"
    );
}
