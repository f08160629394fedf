//! Memory-limit checks made from file headers **before** any pixel data is decoded, and
//! a limited image-crate decoder shared by the PNG/JPEG readers (DEM and ortho).

use std::fs::File;
use std::io::BufReader;
use std::path::Path;

use image::{DynamicImage, ImageDecoder, ImageFormat, ImageReader};

use crate::error::{Error, Result};

/// Refuses a `width x height` grid needing `bytes_per_sample` bytes per sample if the total
/// exceeds `max_memory`, or if either dimension is zero. Overflow counts as too large.
pub(crate) fn check(
    path: &Path,
    width: u64,
    height: u64,
    bytes_per_sample: u64,
    max_memory: u64,
) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(Error::bad_input(
            path,
            format!("image has zero size ({width}x{height})"),
        ));
    }
    let needed = width
        .checked_mul(height)
        .and_then(|n| n.checked_mul(bytes_per_sample))
        .unwrap_or(u64::MAX);
    if needed > max_memory {
        return Err(Error::TooLarge {
            path: path.to_path_buf(),
            needed,
            limit: max_memory,
        });
    }
    Ok(())
}

/// Bytes per sample of the final [`Dem`](super::Dem): one f32 height plus one void flag.
pub(crate) const DEM_BYTES_PER_SAMPLE: u64 = 5;

/// Decodes a PNG or JPEG (format from content, else `fallback`) with the image crate (JPEG
/// strictly, [`crate::fsutil::decode_rgb8`]: truncated data is an error).
/// The header is read first; `check_header(width, height, bytes_per_pixel_of_decoded)`
/// runs before any pixel is decoded, and the decoder's own allocation limit is set to
/// `max_memory`. Errors name the file.
pub(crate) fn decode_image(
    path: &Path,
    fallback: ImageFormat,
    max_memory: u64,
    check_header: impl FnOnce(u32, u32, image::ColorType) -> Result<()>,
) -> Result<DynamicImage> {
    let file = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut reader = ImageReader::new(BufReader::new(file))
        .with_guessed_format()
        .map_err(|e| Error::io(path, e))?;
    if reader.format().is_none() {
        reader.set_format(fallback);
    }
    // Header first without an allocation cap (it allocates little), so our own check
    // reports an oversized image as `TooLarge`; then the decoder gets the cap.
    reader.no_limits();
    let reader_format = reader.format();
    let mut decoder = reader
        .into_decoder()
        .map_err(|e| Error::bad_input(path, format!("cannot read the image header: {e}")))?;
    let (w, h) = decoder.dimensions();
    check_header(w, h, decoder.color_type())?;
    if reader_format == Some(ImageFormat::Jpeg) {
        // strictly, so a truncated JPEG is refused rather than filled in (its size is
        // checked above)
        return crate::fsutil::decode_rgb8(path).map(DynamicImage::ImageRgb8);
    }
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(max_memory);
    decoder
        .set_limits(limits)
        .map_err(|e| Error::bad_input(path, format!("image exceeds the memory limit: {e}")))?;
    DynamicImage::from_decoder(decoder).map_err(|e| {
        Error::bad_input(
            path,
            format!("cannot decode the image (truncated or corrupt?): {e}"),
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn truncated_png_and_jpeg_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let img = image::RgbImage::from_fn(64, 48, |x, y| {
            image::Rgb([
                (x * 37 % 251) as u8,
                (y * 91 % 241) as u8,
                ((x * y) % 256) as u8,
            ])
        });
        for ext in ["png", "jpg"] {
            let full = dir.path().join(format!("full.{ext}"));
            img.save(&full).unwrap();
            let bytes = std::fs::read(&full).unwrap();
            let cut = dir.path().join(format!("cut.{ext}"));
            std::fs::write(&cut, &bytes[..bytes.len() * 3 / 5]).unwrap();
            assert!(
                decode_image(&full, ImageFormat::Png, 1 << 30, |_, _, _| Ok(())).is_ok(),
                "{ext}"
            );
            let e = decode_image(&cut, ImageFormat::Png, 1 << 30, |_, _, _| Ok(()))
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("cut.") && (e.contains("truncated") || e.contains("corrupt")),
                "{ext}: {e}"
            );
            assert!(crate::fsutil::decode_rgb8(&cut).is_err(), "{ext}");
        }
    }

    #[test]
    fn refuses_before_overflow() {
        let p = Path::new("big.tif");
        assert!(check(p, 100, 100, 4, 40_000).is_ok());
        let e = check(p, 100, 101, 4, 40_000).unwrap_err();
        assert!(
            matches!(
                e,
                Error::TooLarge {
                    needed: 40_400,
                    limit: 40_000,
                    ..
                }
            ),
            "{e}"
        );
        assert!(matches!(
            check(p, u64::MAX, 3, 4, u64::MAX - 1).unwrap_err(),
            Error::TooLarge { .. }
        ));
        assert!(
            check(p, 0, 10, 4, 1000)
                .unwrap_err()
                .to_string()
                .contains("big.tif")
        );
    }
}
