//! Benchmark of the prior sweep: 72 assumed tilts (every 5°) of 256 × 256 stimuli, the whole
//! sweep (72 solves, integrations and readings) timed end to end, three runs each, on all
//! cores rayon finds (set RAYON_NUM_THREADS to pin it).
//!
//! `cargo bench --bench analysis` prints one line per stimulus: the three wall times, the
//! median, and how many solves needed the Jacobi fallback. Not criterion: one sample takes
//! seconds, and the figure wanted is the wall time of one sweep.

use shadelab::Boundary;
use shadelab::Method;
use shadelab::SizeRequest;
use shadelab_analysis::analysis::interpretation::analysis_solve_options;
use shadelab_analysis::analysis::{sweep, Domain, Scene, TokenPicture};
use std::time::Instant;

fn main() {
    let cases: [(&str, &[&str], f64, Domain); 4] = [
        ("bumps", &[], 20.0, Domain::Image),
        ("crater", &[], 40.0, Domain::Image),
        ("strips", &[], 24.0, Domain::Image),
        ("hollow-mask", &[], 32.0, Domain::Tokens),
    ];
    let tilts: Vec<f64> = (0..72).map(|i| i as f64 * 5.0).collect();
    println!(
        "prior sweep, 72 tilts, 256 x 256, {} threads",
        rayon::current_num_threads()
    );
    for (name, pairs, ppd, domain) in cases {
        let given = shadelab::Params::parse_pairs(pairs).expect("valid parameters");
        let size = SizeRequest {
            visual_size: Some((256.0 / ppd, 256.0 / ppd)),
            ppd: Some(ppd),
            shape: None,
        };
        let (request, output) =
            shadelab::stimulus::generate(name, &given, &size, 0, 1 << 24).expect("renders");
        let picture = TokenPicture::from_stimulus(&request, &output).expect("a picture");
        let mask = picture.domain(domain);
        let lighting = picture
            .lighting(&mask, 45.0, None, None)
            .expect("a lighting");
        let scene = Scene {
            image: &picture.image,
            domain: &mask,
            boundary: &Boundary::Flat,
            tokens: &picture.tokens,
        };
        let mut times = Vec::new();
        let mut fallbacks = 0;
        for _ in 0..3 {
            let t = Instant::now();
            let s = sweep(&scene, &tilts, &lighting, &analysis_solve_options(), &|| {})
                .expect("the sweep runs");
            times.push(t.elapsed().as_secs_f64());
            fallbacks = s
                .interpretations
                .iter()
                .filter(|i| i.method == Method::Jacobi)
                .count();
        }
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        println!(
            "{name:12} {:.2} s, {:.2} s, {:.2} s (median {:.2} s); {fallbacks} of 72 solves fell back to Jacobi",
            times[0], times[1], times[2], sorted[1]
        );
    }
}
