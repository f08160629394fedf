//! DEM format inference: from the file extension, and for PNG from the IHDR colour type
//! and bit depth (read without decoding). Files with an unknown extension are sniffed by
//! their magic bytes (TIFF, PNG).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use super::DemFormat;
use crate::error::{Error, Result};

const PNG_SIGNATURE: [u8; 8] = [0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];

/// The fields of a PNG IHDR chunk that matter here.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct PngHeader {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Bits per channel (1, 2, 4, 8 or 16).
    pub bit_depth: u8,
    /// PNG colour type: 0 grey, 2 RGB, 3 palette, 4 grey+alpha, 6 RGBA.
    pub colour_type: u8,
}

fn read_prefix(path: &Path, n: usize) -> Result<Vec<u8>> {
    let f = File::open(path).map_err(|e| Error::io(path, e))?;
    let mut buf = Vec::with_capacity(n);
    f.take(n as u64)
        .read_to_end(&mut buf)
        .map_err(|e| Error::io(path, e))?;
    Ok(buf)
}

/// Reads the PNG signature and IHDR chunk of `path`.
pub(crate) fn png_header(path: &Path) -> Result<PngHeader> {
    let b = read_prefix(path, 33)?;
    if b.len() < 8 || b[..8] != PNG_SIGNATURE {
        return Err(Error::bad_input(path, "not a PNG file (bad signature)"));
    }
    if b.len() < 26 || &b[12..16] != b"IHDR" {
        return Err(Error::bad_input(
            path,
            "truncated PNG: no complete IHDR header",
        ));
    }
    let be = |o: usize| u32::from_be_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    Ok(PngHeader {
        width: be(16),
        height: be(20),
        bit_depth: b[24],
        colour_type: b[25],
    })
}

fn is_tiff_magic(b: &[u8]) -> bool {
    matches!(
        b,
        [b'I', b'I', 42 | 43, 0, ..] | [b'M', b'M', 0, 42 | 43, ..]
    )
}

/// Picks the DEM format of `path` from its extension (and PNG header). Errors, naming the
/// file, when the format cannot be inferred or the PNG kind is ambiguous.
pub(crate) fn detect(path: &Path) -> Result<DemFormat> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("tif" | "tiff" | "gtiff") => Ok(DemFormat::Geotiff),
        Some("f32" | "raw" | "bin") => Ok(DemFormat::F32),
        Some("png") => png_kind(path),
        _ => {
            let b = read_prefix(path, 8)?;
            if is_tiff_magic(&b) {
                Ok(DemFormat::Geotiff)
            } else if b == PNG_SIGNATURE {
                png_kind(path)
            } else {
                Err(Error::bad_input(
                    path,
                    "cannot infer the DEM format from the file name; pass --dem-format geotiff|png16|terrain-rgb|f32",
                ))
            }
        }
    }
}

fn png_kind(path: &Path) -> Result<DemFormat> {
    let h = png_header(path)?;
    match (h.colour_type, h.bit_depth) {
        (0 | 4, 16) => Ok(DemFormat::Png16),
        (2 | 6, 8) => Ok(DemFormat::TerrainRgb),
        (0 | 4, bits) => Err(Error::bad_input(
            path,
            format!(
                "is {} {bits}-bit greyscale PNG, too coarse to be taken for a DEM by default; \
                 to read it anyway pass --dem-format png16 with --z-scale (height = value * z-scale + z-offset)",
                if bits == 8 { "an" } else { "a" }
            ),
        )),
        (3, _) => Err(Error::bad_input(
            path,
            "is a palette PNG; if it encodes Terrain-RGB heights pass --dem-format terrain-rgb",
        )),
        (c, bits) => Err(Error::bad_input(
            path,
            format!(
                "is a PNG with colour type {c} at {bits} bits, which is neither a 16-bit greyscale DEM nor \
                 8-bit Terrain-RGB; pass --dem-format to choose a reader"
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn png(dir: &Path, name: &str, img: image::DynamicImage) -> std::path::PathBuf {
        let p = dir.join(name);
        img.save_with_format(&p, image::ImageFormat::Png).unwrap();
        p
    }

    #[test]
    fn formats_from_extension_and_header() {
        let d = tempfile::tempdir().unwrap();
        assert_eq!(detect(Path::new("a/b.TIF")).unwrap(), DemFormat::Geotiff);
        assert_eq!(detect(Path::new("x.tiff")).unwrap(), DemFormat::Geotiff);
        assert_eq!(detect(Path::new("x.f32")).unwrap(), DemFormat::F32);
        assert_eq!(detect(Path::new("x.bin")).unwrap(), DemFormat::F32);
        let g16 = png(
            d.path(),
            "g16.png",
            image::DynamicImage::ImageLuma16(image::ImageBuffer::new(3, 2)),
        );
        assert_eq!(detect(&g16).unwrap(), DemFormat::Png16);
        assert_eq!(
            png_header(&g16).unwrap(),
            PngHeader {
                width: 3,
                height: 2,
                bit_depth: 16,
                colour_type: 0
            }
        );
        let rgb = png(
            d.path(),
            "t.png",
            image::DynamicImage::ImageRgb8(image::ImageBuffer::new(3, 2)),
        );
        assert_eq!(detect(&rgb).unwrap(), DemFormat::TerrainRgb);
        let rgba = png(
            d.path(),
            "t4.png",
            image::DynamicImage::ImageRgba8(image::ImageBuffer::new(3, 2)),
        );
        assert_eq!(detect(&rgba).unwrap(), DemFormat::TerrainRgb);
        let g8 = png(
            d.path(),
            "g8.png",
            image::DynamicImage::ImageLuma8(image::ImageBuffer::new(3, 2)),
        );
        let e = detect(&g8).unwrap_err().to_string();
        assert!(
            e.contains("g8.png") && e.contains("--dem-format png16") && e.contains("8-bit"),
            "{e}"
        );
        // unknown extension: sniffed
        let sniff = d.path().join("noext");
        std::fs::copy(&g16, &sniff).unwrap();
        assert_eq!(detect(&sniff).unwrap(), DemFormat::Png16);
        let junk = d.path().join("junk.dat");
        std::fs::write(&junk, b"hello world").unwrap();
        assert!(
            detect(&junk)
                .unwrap_err()
                .to_string()
                .contains("--dem-format")
        );
    }
}
