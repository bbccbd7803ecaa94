//! Frame files for the fuzzer: PNG mutations that keep the chunk checksums valid (so the decoder, not the CRC check,
//! meets the damage) and valid images of odd sizes, bit depths and colour types, as PNG or TIFF.

use image::{DynamicImage, ImageBuffer, ImageFormat, Luma, LumaA, Rgb, Rgba};
use rand::Rng;
use rand_chacha::ChaCha8Rng;
use std::io::Cursor;

/// CRC-32 (IEEE, as PNG chunks use it) of `bytes`.
pub fn crc32(bytes: &[u8]) -> u32 {
    crc32fast::hash(bytes)
}

/// Chunks of a PNG: (offset of the length field, data length, type); stops at the first malformed chunk.
fn chunks(png: &[u8]) -> Vec<(usize, usize, [u8; 4])> {
    let mut out = Vec::new();
    let mut at = 8;
    while at + 12 <= png.len() {
        let len = u32::from_be_bytes([png[at], png[at + 1], png[at + 2], png[at + 3]]) as usize;
        if at + 12 + len > png.len() {
            break;
        }
        out.push((at, len, [png[at + 4], png[at + 5], png[at + 6], png[at + 7]]));
        at += 12 + len;
    }
    out
}

/// Mutate inside one chunk of `png` (IHDR half the time: size, bit depth, colour type, interlace)
/// and rewrite that chunk's CRC.
pub fn mutate_png_chunk(png: &[u8], rng: &mut ChaCha8Rng) -> Vec<u8> {
    let mut d = png.to_vec();
    let cs = chunks(&d);
    if cs.is_empty() {
        return super::mutate::mutate_bytes(png, rng, 3);
    }
    let (at, len, _) = if rng.random() { cs[0] } else { cs[rng.random_range(0..cs.len())] };
    if len == 0 {
        return d;
    }
    for _ in 0..rng.random_range(1..=3) {
        let pos = at + 8 + rng.random_range(0..len);
        if rng.random_range(0..3) == 0 && len == 13 {
            // IHDR fields: width/height (u32), then bit depth, colour type, compression, filter, interlace
            const VALUES: &[u32] = &[0, 1, 2, 3, 7, 8, 9, 65535, 65536, 0x7fff_ffff, 0xffff_ffff, 100_000];
            let field = at + 8 + 4 * rng.random_range(0..2usize);
            d[field..field + 4].copy_from_slice(&VALUES[rng.random_range(0..VALUES.len())].to_be_bytes());
        } else if rng.random() {
            d[pos] ^= 1 << rng.random_range(0..8);
        } else {
            d[pos] = [0u8, 1, 2, 3, 4, 6, 8, 16, 0xff][rng.random_range(0..9)];
        }
    }
    let crc = crc32(&d[at + 4..at + 8 + len]);
    d[at + 8 + len..at + 12 + len].copy_from_slice(&crc.to_be_bytes());
    d
}

/// A valid image of a random size (often tiny, sometimes large), bit depth and colour type,
/// filled with noise, a constant or a gradient; `(bytes, extension)`.
pub fn odd_image(rng: &mut ChaCha8Rng) -> (Vec<u8>, &'static str) {
    let dim = |rng: &mut ChaCha8Rng| match rng.random_range(0..4) {
        0 => rng.random_range(1..=9u32),
        1 => rng.random_range(8..=40u32),
        2 => rng.random_range(40..=400u32),
        _ => [1u32, 2, 7, 8, 9, 16, 1000, 1500][rng.random_range(0..8)],
    };
    let (w, h) = (dim(rng), dim(rng));
    let fill = rng.random_range(0..3);
    let value = |rng: &mut ChaCha8Rng, x: u32, y: u32| -> u16 {
        match fill {
            0 => rng.random(),
            1 => 0xffff,
            _ => ((x * 257 + y * 97) % 65536) as u16,
        }
    };
    let img = match rng.random_range(0..7) {
        0 | 1 => DynamicImage::ImageLuma8(ImageBuffer::from_fn(w, h, |x, y| Luma([(value(rng, x, y) >> 8) as u8]))),
        2 | 3 => DynamicImage::ImageLuma16(ImageBuffer::from_fn(w, h, |x, y| Luma([value(rng, x, y)]))),
        4 => DynamicImage::ImageLumaA8(ImageBuffer::from_fn(w, h, |x, y| LumaA([(value(rng, x, y) >> 8) as u8, 255]))),
        5 => DynamicImage::ImageRgb8(ImageBuffer::from_fn(w, h, |x, y| {
            let v = (value(rng, x, y) >> 8) as u8;
            Rgb([v, v, v])
        })),
        _ => DynamicImage::ImageRgba16(ImageBuffer::from_fn(w, h, |x, y| {
            let v = value(rng, x, y);
            Rgba([v, v, v, 65535])
        })),
    };
    // the TIFF encoder has no gray + alpha
    let tiff = rng.random() && !matches!(img, DynamicImage::ImageLumaA8(_));
    let (format, ext) = if tiff { (ImageFormat::Tiff, "tif") } else { (ImageFormat::Png, "png") };
    (encode(&img, format), ext)
}

/// `img` encoded as `format` (PNG or TIFF).
pub fn encode(img: &DynamicImage, format: ImageFormat) -> Vec<u8> {
    let mut buf = Cursor::new(Vec::new());
    img.write_to(&mut buf, format).expect("encoding an in-memory image");
    buf.into_inner()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crc32_matches_the_png_reference() {
        // the IEND chunk's CRC is fixed by the PNG specification
        assert_eq!(crc32(b"IEND"), 0xae42_6082);
        assert_eq!(crc32(b"123456789"), 0xcbf4_3926);
    }
}
