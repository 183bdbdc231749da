//! shadelab's integration tests: one binary (one link step) with a module per area.

mod analysis;
mod browser;
mod chromium;
mod cli;
mod determinism;
mod docs;
mod evaluation;
mod experiment;
mod fast_solver;
mod figures;
mod fit;
mod fuzz_regressions;
mod golden_outputs;
mod hostile;
mod interrupt;
mod lightness;
mod mesh;
mod outline;
mod output_sets;
mod perception;
mod python;
mod robustness;
mod sidecar_input;
mod solve;
mod stimuli;
mod teaching;
