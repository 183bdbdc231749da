//! Image and mask loading on arbitrary bytes, as `solve` reads them: an image (PNG or `.npy`)
//! and a PNG mask, then the mask-size check. The first byte picks the image format; the next
//! two give the image's length (little endian); the rest after the image is the mask.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shadelab::io;
use std::path::Path;

/// The pixel cap used here (the CLI's default is 64 Mpx; a smaller cap keeps the fuzzer inside
/// its memory limit while still exercising the check).
const MAX_PIXELS: usize = 4 * 1024 * 1024;

fuzz_target!(|data: &[u8]| {
    if data.len() < 3 {
        return;
    }
    let npy = data[0] & 1 == 1;
    let split = (usize::from(data[1]) | usize::from(data[2]) << 8).min(data.len() - 3);
    let (image_bytes, mask_bytes) = data[3..].split_at(split);
    let image = if npy {
        if let Ok(array) =
            io::read_array_from_bytes(image_bytes, Path::new("image.npy"), MAX_PIXELS)
        {
            // The rule for a picture's integers, and the range check every picture passes.
            if let Ok(Some(scale)) = io::npy_scale(&array.dtype) {
                let scaled: Vec<f64> = array.data.iter().map(|v| v / scale.max).collect();
                let _ = io::check_luminance_range(&scaled, Path::new("image.npy"));
            }
        }
        io::read_image_from_bytes(image_bytes, Path::new("image.npy"), MAX_PIXELS)
    } else {
        io::read_gray_from_bytes(image_bytes, Path::new("image.png"), MAX_PIXELS).map(|(i, _)| i)
    };
    let mask = io::read_mask_from_bytes(mask_bytes, Path::new("mask.png"), MAX_PIXELS);
    if let (Ok(image), Ok(mask)) = (image, mask) {
        if mask.same_size(&image) {
            assert!(mask.count() <= image.width() * image.height());
        }
    }
});
