//! The image decoders textures and environments read (EXR, PFM, PNG, TGA): the first byte picks
//! the format (its low two bits) and whether 8-bit values are sRGB-decoded (bit 2), the rest is
//! the file. An image comes back with as many texels as its size says, and a bilinear texture
//! lookup on it under every wrap mode is finite wherever its texels are; otherwise the error
//! says why.
#![no_main]

use dpm::image_io::{SceneImageFormat, decode_linear_within};
use dpm::scene::texture::{TextureImage, Wrap};
use glam::Vec2;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&selector, file)) = data.split_first() else {
        return;
    };
    let format = [
        SceneImageFormat::Exr,
        SceneImageFormat::Pfm,
        SceneImageFormat::Png,
        SceneImageFormat::Tga,
    ][usize::from(selector & 3)];
    // Within the fuzzer's 64 MB an allocation: a quarter of a million texels (12 bytes each).
    match decode_linear_within(file, format, selector & 4 != 0, 1 << 18) {
        Ok(image) => {
            assert!(image.width > 0 && image.height > 0);
            assert_eq!(image.pixels.len(), image.width * image.height);
            let texture = TextureImage {
                width: image.width,
                height: image.height,
                texels: image.pixels,
            };
            if texture.check_finite().is_ok() {
                for wrap in [Wrap::Repeat, Wrap::Black, Wrap::Clamp] {
                    for st in [
                        Vec2::new(0.3, 0.7),
                        Vec2::new(-1.5, 2.25),
                        Vec2::splat(1e30),
                    ] {
                        assert!(texture.bilinear(st, wrap).is_finite(), "{st} {wrap:?}");
                    }
                }
            }
        }
        Err(message) => assert!(!message.is_empty()),
    }
});
