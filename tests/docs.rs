//! The documentation kept honest: the command-line reference is the program's own `--help`, the
//! tutorial's commands run as written and print what it shows, every image and relative link of
//! docs/*.md and README.md resolves, and every gallery preset links to a page and heading that
//! exist. `SHADELAB_BLESS=1 cargo test --test tests docs` rewrites docs/cli.md.

use crate::cli::{scratch, shadelab};
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// The subcommands listed under `Commands:` in a `--help` text, without `help`.
pub fn subcommands(help: &str) -> Vec<String> {
    help.lines()
        .skip_while(|l| l.trim_end() != "Commands:")
        .skip(1)
        .take_while(|l| !l.trim().is_empty())
        .filter(|l| l.starts_with("  ") && !l.starts_with("      "))
        .filter_map(|l| l.split_whitespace().next())
        .filter(|name| *name != "help")
        .map(str::to_string)
        .collect()
}

fn help_text(path: &[String]) -> String {
    let mut args: Vec<&str> = path.iter().map(String::as_str).collect();
    args.push("--help");
    let out = shadelab(&std::env::temp_dir(), &args);
    assert!(out.status.success(), "shadelab {args:?} failed");
    String::from_utf8(out.stdout).expect("help is UTF-8")
}

/// docs/cli.md as the program's help makes it: every command and subcommand, depth first in
/// the order `--help` lists them.
fn cli_reference() -> String {
    let mut md = String::from(
        "# Command-line reference\n\n\
         Every command's `--help`, exactly as `shadelab` prints it. This file is generated: the test\n\
         `docs::the_cli_reference_is_the_programs_help` fails when it differs from the program, and\n\
         `SHADELAB_BLESS=1 cargo test --release --test tests docs::the_cli_reference` rewrites it.\n\
         Conventions (axes, lights, sizes, files) are in [conventions.md](conventions.md).\n",
    );
    let mut stack: Vec<Vec<String>> = vec![vec![]];
    let mut sections = Vec::new();
    while let Some(path) = stack.pop() {
        let help = help_text(&path);
        // Push in reverse so the listing order is kept.
        for sub in subcommands(&help).into_iter().rev() {
            let mut p = path.clone();
            p.push(sub);
            stack.push(p);
        }
        sections.push((path, help));
    }
    md.push_str("\nCommands:");
    for (path, _) in sections.iter().skip(1) {
        let name = format!("shadelab {}", path.join(" "));
        md.push_str(&format!(" [`{name}`](#{}),", slug(&name)));
    }
    md.pop();
    md.push_str(".\n");
    for (path, help) in &sections {
        let title = if path.is_empty() {
            "shadelab".to_string()
        } else {
            format!("shadelab {}", path.join(" "))
        };
        md.push_str(&format!("\n## {title}\n\n```text\n{}```\n", help));
    }
    md
}

#[test]
fn the_cli_reference_is_the_programs_help() {
    let want = cli_reference();
    // Every top-level command has a section, so a new command cannot go unnoticed.
    let top = subcommands(&help_text(&[]));
    assert!(top.len() >= 8, "{top:?}");
    for c in &top {
        assert!(want.contains(&format!("\n## shadelab {c}\n")), "{c}");
    }
    let path = root().join("docs/cli.md");
    if std::env::var("SHADELAB_BLESS").is_ok_and(|v| v == "1") {
        std::fs::write(&path, &want).unwrap();
        return;
    }
    let have = std::fs::read_to_string(&path).unwrap_or_default();
    if have != want {
        let first = have
            .lines()
            .zip(want.lines())
            .position(|(a, b)| a != b)
            .unwrap_or(have.lines().count().min(want.lines().count()));
        panic!(
            "docs/cli.md differs from the program's --help from line {} on (now: {:?}); \
             run SHADELAB_BLESS=1 cargo test --test tests docs::the_cli_reference to rewrite it",
            first + 1,
            want.lines().nth(first)
        );
    }
}

#[test]
fn subcommands_are_read_from_the_help_listing() {
    let help = "Usage: x\n\nCommands:\n  render  Render\n  a-b     Two\n          continued\n  help    Print\n\nOptions:\n  -h\n";
    assert_eq!(subcommands(help), ["render", "a-b"]);
    assert!(subcommands("Usage: x\n\nOptions:\n  --quiet\n").is_empty());
}

/// The fenced blocks of `lang` in a markdown text, in order.
pub fn fenced_blocks(md: &str, lang: &str) -> Vec<String> {
    let mut blocks = Vec::new();
    let mut current: Option<String> = None;
    for line in md.lines() {
        match &mut current {
            None if line.trim_end() == format!("```{lang}") => current = Some(String::new()),
            Some(_) if line.trim_end() == "```" => blocks.extend(current.take()),
            Some(b) => {
                b.push_str(line);
                b.push('\n');
            }
            None => {}
        }
    }
    blocks
}

/// Runs `script` with bash (`-euo pipefail`) in `dir`, the shadelab binary first on the PATH.
fn run_script(script: &str, dir: &Path) -> std::process::Output {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_shadelab")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new("bash")
        .args(["-euo", "pipefail", "-c", script])
        .env("PATH", path)
        .current_dir(dir)
        .output()
        .expect("bash runs")
}

/// Every `shadelab` command of the README's shell blocks runs as written, in order, in an empty
/// folder (the `cargo` lines — the gallery, the tests and the examples — are run elsewhere).
#[test]
fn the_readme_commands_run_as_written() {
    let md = read(&root().join("README.md"));
    let script: String = fenced_blocks(&md, "sh")
        .join("")
        .lines()
        .filter(|l| !l.trim_start().starts_with("cargo "))
        .map(|l| format!("{l}\n"))
        .collect();
    let commands = script
        .lines()
        .filter(|l| l.starts_with("shadelab "))
        .count();
    assert!(commands >= 10, "{script}");
    let d = scratch("readme");
    let out = run_script(&script, &d);
    assert!(
        out.status.success(),
        "the README's commands failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "sphere.png",
        "vase_mask.png",
        "vase-sfs/report.json",
        "vase-estimated/report.json",
        "checker-odog/lightness.json",
        "fading/fading.gif",
    ] {
        assert!(d.join(f).exists(), "{f}");
    }
    // The first vase was rendered with --layers, the second without: the second set replaced
    // the first whole, its layers included.
    assert!(!d.join("vase_depth.npy").exists());
}

#[test]
fn the_tutorial_runs_as_written_and_prints_what_it_shows() {
    let md = read(&root().join("docs/tutorial.md"));
    let script = fenced_blocks(&md, "sh").join("");
    assert!(script.contains("shadelab render") && script.contains("study run"));
    let d = scratch("tutorial");
    let out = run_script(&script, &d);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "the tutorial's commands failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for f in [
        "bump.png",
        "sweep/sweep.png",
        "sweep/sweep.csv",
        "observer/p_convex.png",
        "study/results.csv",
    ] {
        assert!(d.join(f).exists(), "{f}");
    }
    // Every line of the tutorial's sample outputs is printed by its commands (numbers to 10⁻³,
    // so that a better solver does not fail the tutorial, a wrong one does).
    let printed: Vec<&str> = stdout.lines().collect();
    let shown = fenced_blocks(&md, "text");
    assert!(shown.len() >= 3);
    for block in shown {
        for line in block.lines().filter(|l| *l != "...") {
            assert!(
                printed.iter().any(|p| same_line(line, p)),
                "the tutorial shows '{line}' but its commands print:\n{stdout}"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// Whether two comma-separated lines agree: text fields exactly, numbers to a relative 10⁻³
/// (or 10⁻⁶ near zero).
fn same_line(shown: &str, printed: &str) -> bool {
    let (a, b): (Vec<&str>, Vec<&str>) = (shown.split(',').collect(), printed.split(',').collect());
    a.len() == b.len()
        && a.iter()
            .zip(&b)
            .all(|(x, y)| match (x.parse::<f64>(), y.parse::<f64>()) {
                (Ok(u), Ok(v)) => (u - v).abs() <= 1e-6_f64.max(1e-3 * u.abs().max(v.abs())),
                _ => x == y,
            })
}

#[test]
fn sample_output_lines_compare_numbers_loosely_and_text_exactly() {
    assert!(same_line(
        "0,0.14088781716,7.0368",
        "0,0.1408878300738346,7.03684990739765"
    ));
    assert!(same_line("90,0.000000006", "90,0.000000005127"));
    assert!(!same_line("0,0.1409", "0,-0.1409"));
    assert!(!same_line("0,0.1409", "0,0.1409,1"));
    assert!(!same_line("bump,1", "dimple,1"));
}

/// GitHub's anchor for a heading: lower case, punctuation dropped, spaces to hyphens.
pub fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
        .map(|c| if c == ' ' { '-' } else { c })
        .collect()
}

/// The anchors of a markdown file's headings (outside code blocks), with GitHub's `-1`, `-2`
/// suffixes for repeats.
pub fn anchors(md: &str) -> BTreeSet<String> {
    let mut seen = BTreeSet::new();
    for line in without_code(md).lines() {
        let hashes = line.chars().take_while(|&c| c == '#').count();
        if (1..=6).contains(&hashes) && line[hashes..].starts_with(' ') {
            let base = slug(&line[hashes..]);
            let mut a = base.clone();
            let mut k = 1;
            while seen.contains(&a) {
                a = format!("{base}-{k}");
                k += 1;
            }
            seen.insert(a);
        }
    }
    seen
}

/// The text with fenced blocks and inline code removed (links there are examples).
fn without_code(md: &str) -> String {
    let mut out = String::new();
    let mut fenced = false;
    for line in md.lines() {
        if line.trim_start().starts_with("```") {
            fenced = !fenced;
            continue;
        }
        if fenced {
            continue;
        }
        let mut inline = false;
        for c in line.chars() {
            if c == '`' {
                inline = !inline;
            } else if !inline {
                out.push(c);
            }
        }
        out.push('\n');
    }
    out
}

/// The targets of markdown links and images, and of `src="…"`/`href="…"` attributes.
pub fn link_targets(md: &str) -> Vec<String> {
    let text = without_code(md);
    let mut targets = Vec::new();
    let mut rest = text.as_str();
    while let Some(i) = rest.find("](") {
        rest = &rest[i + 2..];
        if let Some(end) = rest.find(')') {
            let t = rest[..end].split_whitespace().next().unwrap_or("");
            targets.push(t.to_string());
        }
    }
    for attr in ["src=\"", "href=\""] {
        let mut rest = text.as_str();
        while let Some(i) = rest.find(attr) {
            rest = &rest[i + attr.len()..];
            if let Some(end) = rest.find('"') {
                targets.push(rest[..end].to_string());
            }
        }
    }
    targets
}

/// What is wrong with a relative link `target` from the markdown file `from`, if anything.
pub fn check_link(from: &Path, target: &str) -> Option<String> {
    if target.contains("://") || target.starts_with("mailto:") {
        return None;
    }
    let (file, anchor) = match target.split_once('#') {
        Some((f, a)) => (f, Some(a)),
        None => (target, None),
    };
    let path = if file.is_empty() {
        from.to_path_buf()
    } else {
        normalise(&from.parent().unwrap().join(file))
    };
    if !path.exists() {
        return Some(format!(
            "{}: '{target}' does not exist ({})",
            from.display(),
            path.display()
        ));
    }
    match anchor {
        Some(a) if path.extension().is_some_and(|e| e == "md") => {
            (!anchors(&read(&path)).contains(a)).then(|| {
                format!(
                    "{}: '{target}': no heading with anchor #{a} in {}",
                    from.display(),
                    path.display()
                )
            })
        }
        _ => None,
    }
}

/// `a/b/../c` as `a/c`, without touching the disk (a gallery folder need not exist).
fn normalise(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            std::path::Component::ParentDir => {
                out.pop();
            }
            std::path::Component::CurDir => {}
            other => out.push(other),
        }
    }
    out
}

fn doc_files() -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(root().join("docs"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "md"))
        // The documentation site's front page links the site's pages and its gallery, which
        // exist only in the built site: docs/site/build.sh checks those links (Sphinx with -W,
        // then the gallery's).
        .filter(|p| !p.ends_with("docs/index.md"))
        .collect();
    files.sort();
    files.push(root().join("README.md"));
    files
}

#[test]
fn every_image_and_relative_link_in_the_docs_resolves() {
    let mut problems = Vec::new();
    let mut checked = 0;
    for file in doc_files() {
        for target in link_targets(&read(&file)) {
            checked += 1;
            problems.extend(check_link(&file, &target));
        }
    }
    assert!(checked > 50, "only {checked} links found");
    assert!(
        problems.is_empty(),
        "broken links:\n{}",
        problems.join("\n")
    );
}

#[test]
fn the_link_checker_finds_missing_files_and_anchors() {
    let d = scratch("links");
    std::fs::write(
        d.join("a.md"),
        "# The f–g space (stereographic)\n## Light from above\n## Light from above\n\
         ![x](b.png) [y](a.md#light-from-above-1) `[z](gone.md)`\n```\n[w](gone2.md)\n```\n\
         <img src=\"c.png\"> [u](https://example.org/x)\n",
    )
    .unwrap();
    std::fs::write(d.join("b.png"), "").unwrap();
    let md = read(&d.join("a.md"));
    assert_eq!(
        anchors(&md),
        BTreeSet::from([
            "the-fg-space-stereographic".to_string(),
            "light-from-above".into(),
            "light-from-above-1".into()
        ])
    );
    let targets = link_targets(&md);
    assert_eq!(
        targets,
        [
            "b.png",
            "a.md#light-from-above-1",
            "https://example.org/x",
            "c.png"
        ]
    );
    let a = d.join("a.md");
    assert_eq!(check_link(&a, "b.png"), None);
    assert_eq!(check_link(&a, "a.md#light-from-above-1"), None);
    assert!(check_link(&a, "c.png").unwrap().contains("does not exist"));
    assert!(check_link(&a, "a.md#light-from-below")
        .unwrap()
        .contains("no heading"));
    assert!(check_link(&a, "#nowhere").unwrap().contains("no heading"));
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn every_gallery_preset_is_explained_on_a_docs_page_that_exists() {
    let presets = shadelab_stimuli::gallery::builtin_presets().unwrap();
    let readme = root().join("README.md");
    for p in &presets {
        let caption = p.spec.caption.as_deref().unwrap_or("");
        assert!(caption.len() > 40, "{}: no explanation", p.name);
        let docs = p
            .spec
            .docs
            .as_deref()
            .unwrap_or_else(|| panic!("stimuli/{}.json has no \"docs\" link", p.name));
        assert!(
            docs.starts_with("docs/") && docs.contains(".md#"),
            "{}: {docs}",
            p.name
        );
        // The link is relative to the repository root, as README.md's are.
        if let Some(problem) = check_link(&readme, docs) {
            panic!("stimuli/{}.json: {problem}", p.name);
        }
    }
}

#[test]
fn the_gallery_page_links_each_picture_to_its_explanation() {
    use shadelab::pipeline::gallery::GalleryConfig;
    use shadelab::{CommandReport, NoProgress, Output};
    use shadelab_stimuli::gallery::{Options, Preset};
    let d = scratch("gallery-links");
    let spec: shadelab::stimulus::Spec = serde_json::from_str(
        r#"{"stimulus": "disc", "shape": [16, 16], "title": "A disc",
            "caption": "A plain disc.", "docs": "docs/priors.md#light-from-above"}"#,
    )
    .unwrap();
    let presets = [Preset {
        name: "disc".into(),
        spec,
        source: "disc.json".into(),
    }];
    let html = |dir: &str, base: Option<&str>| {
        let config = GalleryConfig {
            presets: presets.to_vec(),
            options: Options {
                docs_base: base.map(str::to_string),
                ..Options::default()
            },
            source: None,
        };
        let report = shadelab::gallery(&config, &NoProgress).unwrap();
        report.write(&Output::new(d.join(dir))).unwrap();
        read(&d.join(dir).join("index.html"))
    };
    // By default nothing links outside the folder: the card carries the section's text.
    let alone = html("f", None);
    assert!(
        !alone.contains("../") && !alone.contains("docs/priors.md#"),
        "{alone}"
    );
    assert!(alone.contains("<h3>Light from above</h3>") && alone.contains("Discs bright on top"));
    assert!(html("g", Some("../")).contains(r##"<a href="../docs/priors.md#light-from-above">"##));
    assert!(
        html("h", Some("https://example.org/shadelab/blob/main")).contains(
            r##"href="https://example.org/shadelab/blob/main/docs/priors.md#light-from-above""##
        )
    );
    // From README's gallery/ the default link reaches the real page.
    let from_gallery = root().join("gallery").join("index.md");
    assert_eq!(
        check_link(&from_gallery, "../docs/priors.md#light-from-above"),
        None
    );
    let _ = std::fs::remove_dir_all(&d);
}

#[test]
fn render_space_is_the_space_parameter_and_refused_where_there_is_none() {
    let d = scratch("render-space");
    let run = |args: &[&str]| shadelab(&d, args);
    let base = [
        "render",
        "reflectance-map",
        "--size",
        "48",
        "--light",
        "left",
    ];
    for (extra, out) in [
        (["--space", "fg"], "flag.png"),
        (["--set", "space=fg"], "set.png"),
        (["--space", "pq"], "pq.png"),
    ] {
        let mut args = base.to_vec();
        args.extend(extra);
        args.extend(["--out", out]);
        let o = run(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let png = |f: &str| std::fs::read(d.join(f)).unwrap();
    assert_eq!(png("flag.png"), png("set.png"));
    assert_ne!(png("flag.png"), png("pq.png"));
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("flag.json")).unwrap()).unwrap();
    assert_eq!(meta["parameters"]["space"], "fg", "{meta}");
    crate::cli::assert_error(
        &run(&["render", "sphere", "--space", "fg", "--out", "s.png"]),
        2,
        "--space",
    );
    crate::cli::assert_error(
        &run(&[&base[..], &["--space", "xy", "--out", "x.png"]].concat()),
        2,
        "space",
    );
    assert!(!d.join("s.png").exists() && !d.join("x.png").exists());
    let _ = std::fs::remove_dir_all(&d);
}
