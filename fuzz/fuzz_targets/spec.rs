//! The spec parsers on arbitrary bytes. The first byte picks what the rest is:
//! - 0: a stimulus spec / gallery preset (JSON `Spec`), prepared and, when small, generated;
//! - 1: a stimulus name on the first line and `key=value` parameters on the others
//!   (`Params::parse_pairs`, as `render --set`), prepared and, when small, generated;
//! - 2: a study spec (JSON `StudySpec`), checked and expanded by `Study::new`.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shadelab::analysis::study::{Shard, Study, StudySpec};
use shadelab::params::Params;
use shadelab::stimulus::{self, Spec};
use shadelab::visual_size::SizeRequest;

/// The largest frame the target prepares (rendering bigger images only measures speed).
const MAX_PIXELS: usize = 16 * 1024;

/// Stimuli that read a file named by a parameter: the other targets cover those readers, and a
/// fuzzer must not open arbitrary paths.
const READS_FILES: &[&str] = &["heightfield", "mesh"];

/// Prepares the stimulus at the size asked for (checking the size triple against the cap), and
/// generates it at a small fixed shape with the same resolution, so that every parameter set
/// that passes its checks is rendered whatever size it asks for.
fn prepare_and_generate(
    name: &str,
    params: &serde_json::Map<String, serde_json::Value>,
    size: &SizeRequest,
    seed: u64,
) {
    // Oversized requests fail here with an error; the parameters still get rendered below.
    let _ = stimulus::prepare(name, params, size, seed, MAX_PIXELS);
    if READS_FILES.contains(&name) {
        return;
    }
    let small = SizeRequest {
        visual_size: None,
        ppd: size.ppd,
        shape: Some((32, 48)),
    };
    let Ok((stim, request)) = stimulus::prepare(name, params, &small, seed, MAX_PIXELS) else {
        return;
    };
    let (w, h) = (request.geometry.width, request.geometry.height);
    if w.saturating_mul(h) <= MAX_PIXELS {
        let _ = stim.generate(&request);
    }
}

fuzz_target!(|data: &[u8]| {
    let Some((&selector, rest)) = data.split_first() else {
        return;
    };
    match selector % 3 {
        0 => {
            if let Ok(spec) = serde_json::from_slice::<Spec>(rest) {
                prepare_and_generate(
                    &spec.stimulus,
                    &spec.params,
                    &spec.size(),
                    spec.seed.unwrap_or(0),
                );
            }
        }
        1 => {
            let text = String::from_utf8_lossy(rest);
            let mut lines = text.lines();
            let name = lines.next().unwrap_or("").trim().to_string();
            let pairs: Vec<&str> = lines.collect();
            let Ok(params) = Params::parse_pairs(&pairs) else {
                return;
            };
            prepare_and_generate(&name, &params, &SizeRequest::default(), 0);
        }
        _ => {
            if let Ok(spec) = serde_json::from_slice::<StudySpec>(rest) {
                if let Ok(study) = Study::new(spec) {
                    let _ = study.shard_points(Shard { index: 0, count: 2 });
                }
            }
            let _ = Shard::parse(&String::from_utf8_lossy(rest));
        }
    }
});
