//! shadelab's integration tests: one binary (one link step) with a module per area.

mod analysis;
mod cli;
mod fast_solver;
mod lightness;
mod mesh;
mod solve;
mod stimuli;
