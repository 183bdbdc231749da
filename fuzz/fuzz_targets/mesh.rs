//! Mesh parsers (PLY ASCII/binary, OBJ) on arbitrary bytes, then rasterisation of whatever
//! parses. The first byte picks the format, the shading and the view; the rest is the file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shadelab::surface::{view_rotation, Mesh, MeshShading};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, file)) = data.split_first() else {
        return;
    };
    let mesh = if selector & 1 == 0 {
        Mesh::from_ply(file, Path::new("fuzz.ply"))
    } else {
        Mesh::from_obj(file, Path::new("fuzz.obj"))
    };
    let Ok(mesh) = mesh else {
        return;
    };
    let shading = if selector & 2 == 0 {
        MeshShading::Smooth
    } else {
        MeshShading::Flat
    };
    // Six view bits: yaw and pitch in steps of 45 degrees.
    let yaw = f64::from((selector >> 2) & 7) * 45.0;
    let pitch = f64::from(selector >> 5) * 45.0;
    let Ok(view) = view_rotation(yaw, pitch, 0.0) else {
        return;
    };
    // Errors (no pixel covered, a mesh seen as a point) are fine; panics are not.
    let _ = mesh.rasterize_with(32, 24, &view, 0.9, shading);
});
