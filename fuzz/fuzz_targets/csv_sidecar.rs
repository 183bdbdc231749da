//! The study shard tables and render sidecars on arbitrary bytes, as `study merge` and every
//! reader of an image's sidecar take them. Byte 0 mod 3 picks the mode; byte 1 the shard and
//! the study's size; the rest is the file:
//! - 0: a shard's `results.csv` → `study::merge::shard_rows` (header, field count, numbers,
//!   point ids against the shard and the study), then `io::csv_record` of every line;
//! - 1: the same for `sweep.csv`;
//! - 2: a render sidecar (JSON) → `RenderSidecar::from_value`, and for every sidecar that
//!   reads, what the readers ask of it (summary, target names, linearised values, the declared
//!   albedo, ambient and light).
#![no_main]

use libfuzzer_sys::fuzz_target;
use shadelab::analysis::study::{merge::shard_rows, Shard, RESULTS, SWEEP};
use shadelab::io::{self, Declared, RenderSidecar};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let [selector, shape, rest @ ..] = data else {
        return;
    };
    let count = usize::from(shape & 7) + 1;
    let shard = Shard {
        index: usize::from(shape >> 3) % count,
        count,
    };
    let points = usize::from(shape >> 5) * 3;
    match selector % 3 {
        mode @ (0 | 1) => {
            let file = if mode == 0 { RESULTS } else { SWEEP };
            let path = Path::new("shard").join(file);
            if let Ok(rows) = shard_rows(rest, &path, shard, points) {
                for (point, line) in rows {
                    assert!(point < points && shard.runs(point));
                    assert!(line.ends_with('\n'));
                }
            }
            for line in String::from_utf8_lossy(rest).lines() {
                let _ = io::csv_record(line);
            }
        }
        _ => {
            let Ok(value) = serde_json::from_slice::<serde_json::Value>(rest) else {
                return;
            };
            if let Ok(sidecar) = RenderSidecar::from_value(Path::new("dir/image.json"), &value) {
                let _ = sidecar.summary();
                let _ = sidecar.target_names();
                let _ = sidecar.object_mask();
                for v in [0.0, 0.25, 1.0] {
                    let _ = sidecar.linearise(v);
                }
            }
            let _ = Declared::from_record(&value["parameters"], &value["notes"]);
        }
    }
});
