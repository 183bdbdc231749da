//! shadelab's integration tests: one binary (one link step) with a module per area.

mod cli;
mod mesh;
mod solve;
mod stimuli;
