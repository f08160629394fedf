//! Atomic file output: every file cliffmap writes appears complete or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::{Error, Result};

/// Writes `bytes` to `path` atomically: a temporary file in the same directory is written,
/// flushed to disk and renamed over `path`. Parent directories are created. On error the
/// temporary file is removed and `path` is left as it was.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let tmp = temp_path(path);
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        test_disk_budget(bytes.len())?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    result.map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

/// Fault injection for the full-disk tests where no small file system can be mounted:
/// with `CLIFFMAP_TEST_DISK_BYTES=N` in the environment, writes fail with ENOSPC ("No
/// space left on device") once this process has written more than N bytes through
/// [`write_atomic`]. Unset (always, outside tests), it does nothing.
fn test_disk_budget(len: usize) -> std::io::Result<()> {
    use std::sync::OnceLock;
    use std::sync::atomic::{AtomicU64, Ordering};
    static LIMIT: OnceLock<Option<u64>> = OnceLock::new();
    static USED: AtomicU64 = AtomicU64::new(0);
    let limit = LIMIT.get_or_init(|| {
        std::env::var("CLIFFMAP_TEST_DISK_BYTES")
            .ok()
            .and_then(|v| v.parse().ok())
    });
    if let Some(limit) = *limit {
        let used = USED.fetch_add(len as u64, Ordering::SeqCst) + len as u64;
        if used > limit {
            return Err(std::io::Error::from_raw_os_error(28));
        }
    }
    Ok(())
}

/// PNG compression of store textures (`--png-compression`): the same pixels, a trade of
/// encoding time against file size (docs/performance.md, "PNG encoding"; measured on
/// 2048² photo textures: `fast` ≈ 18× the speed of `balanced` at 1.3× its size).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PngCompression {
    /// fdeflate with adaptive filtering: the fastest encoder, the `image` crate's default
    /// and what every store before the knob was written with. The default.
    #[default]
    Fast,
    /// A balanced zlib level: ~0.77× the size of `fast` at ~1/18 of its speed.
    Balanced,
    /// The strongest zlib level: the smallest files, slowest.
    Best,
}

impl std::str::FromStr for PngCompression {
    type Err = String;

    /// `fast`, `balanced` or `best`.
    fn from_str(s: &str) -> std::result::Result<PngCompression, String> {
        match s {
            "fast" => Ok(PngCompression::Fast),
            "balanced" => Ok(PngCompression::Balanced),
            "best" => Ok(PngCompression::Best),
            _ => Err(format!(
                "unknown PNG compression {s:?} (fast, balanced or best)"
            )),
        }
    }
}

impl PngCompression {
    fn codec(self) -> image::codecs::png::CompressionType {
        use image::codecs::png::CompressionType;
        match self {
            PngCompression::Fast => CompressionType::Fast,
            PngCompression::Balanced => CompressionType::Default,
            PngCompression::Best => CompressionType::Best,
        }
    }
}

/// Encodes an image as PNG in memory with `compression`; `path` names the destination in
/// errors.
pub fn encode_png<P, C>(
    path: &Path,
    img: &image::ImageBuffer<P, C>,
    compression: PngCompression,
) -> Result<Vec<u8>>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    use image::EncodableLayout;
    use image::ImageEncoder;
    use image::codecs::png::{FilterType, PngEncoder};
    let mut buf = Vec::new();
    PngEncoder::new_with_quality(&mut buf, compression.codec(), FilterType::Adaptive)
        .write_image(img.as_bytes(), img.width(), img.height(), P::COLOR_TYPE)
        .map_err(|e| Error::io(path, std::io::Error::other(e)))?;
    Ok(buf)
}

/// Encodes an image as PNG (fast compression) and writes it atomically.
pub fn write_png_atomic<P, C>(path: &Path, img: &image::ImageBuffer<P, C>) -> Result<()>
where
    P: image::PixelWithColorType,
    [P::Subpixel]: image::EncodableLayout,
    C: std::ops::Deref<Target = [P::Subpixel]>,
{
    write_atomic(path, &encode_png(path, img, PngCompression::Fast)?)
}

/// The temporary sibling used while writing `path` (unique per process and thread).
fn temp_path(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tid = format!("{:?}", std::thread::current().id())
        .replace(|c: char| !c.is_ascii_alphanumeric(), "");
    path.with_file_name(format!(".{name}.{}.{tid}.tmp", std::process::id()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_png_compression_keeps_the_pixels_and_fast_is_the_old_encoding() {
        let img = image::RgbaImage::from_fn(97, 61, |x, y| {
            image::Rgba([
                (x * 7 % 256) as u8,
                (y * 13 % 256) as u8,
                ((x ^ y) % 256) as u8,
                255,
            ])
        });
        let p = Path::new("t.png");
        for c in [
            PngCompression::Fast,
            PngCompression::Balanced,
            PngCompression::Best,
        ] {
            let bytes = encode_png(p, &img, c).unwrap();
            assert_eq!(
                image::load_from_memory(&bytes).unwrap().to_rgba8(),
                img,
                "{c:?}"
            );
        }
        let mut old = std::io::Cursor::new(Vec::new());
        img.write_to(&mut old, image::ImageFormat::Png).unwrap();
        let old = old.into_inner();
        assert_eq!(encode_png(p, &img, PngCompression::Fast).unwrap(), old);
        assert!(encode_png(p, &img, PngCompression::Balanced).unwrap().len() < old.len());
    }

    #[test]
    fn writes_and_replaces_without_leftovers() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("sub/a.bin");
        write_atomic(&p, b"one").unwrap();
        write_atomic(&p, b"two").unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), b"two");
        let names: Vec<_> = std::fs::read_dir(dir.path().join("sub")).unwrap().collect();
        assert_eq!(names.len(), 1);
    }
}

/// `path` written relative to the directory `base` (e.g. `../photos/a.jpg`), with `/`
/// separators, so records stay valid when the two are moved together; `path` as given if
/// either cannot be resolved or they share no root.
pub fn relative_path(path: &Path, base: &Path) -> String {
    let (Ok(p), Ok(b)) = (path.canonicalize(), base.canonicalize()) else {
        return path.display().to_string();
    };
    let (pc, bc): (Vec<_>, Vec<_>) = (p.components().collect(), b.components().collect());
    let common = pc.iter().zip(&bc).take_while(|(x, y)| x == y).count();
    if common == 0 {
        return path.display().to_string();
    }
    let mut parts: Vec<String> = vec!["..".to_string(); bc.len() - common];
    parts.extend(
        pc[common..]
            .iter()
            .map(|c| c.as_os_str().to_string_lossy().into_owned()),
    );
    parts.join("/")
}

#[cfg(test)]
mod relative_tests {
    use super::relative_path;

    #[test]
    fn relative_paths_climb_to_the_common_ancestor() {
        let t = tempfile::tempdir().unwrap();
        let (store, photos) = (t.path().join("out/store"), t.path().join("out/photos"));
        std::fs::create_dir_all(&store).unwrap();
        std::fs::create_dir_all(&photos).unwrap();
        let img = photos.join("a.jpg");
        std::fs::write(&img, b"x").unwrap();
        assert_eq!(relative_path(&img, &store), "../photos/a.jpg");
        assert_eq!(
            relative_path(&store.join("missing.jpg"), &store),
            store.join("missing.jpg").display().to_string()
        );
    }
}

/// Decodes the image file at `path` to RGB8 (sRGB). JPEG files are decoded in strict mode
/// (`zune-jpeg`, the decoder the `image` crate uses, so valid files give the same pixels): a
/// truncated or damaged file is an error, not an image whose missing part is filled in
/// (the one strict-mode complaint let through is stray bytes between markers, which some
/// cameras write; such a file is then decoded leniently). Other formats go through the
/// `image` crate, whose PNG and TIFF decoders fail on truncated data. Errors name the file.
pub fn decode_rgb8(path: &Path) -> Result<image::RgbImage> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let format = image::guess_format(&bytes)
        .map_err(|e| Error::bad_input(path, format!("unknown image format: {e}")))?;
    if format == image::ImageFormat::Jpeg {
        let decode = |strict: bool| {
            let opts = zune_core::options::DecoderOptions::default()
                .set_strict_mode(strict)
                .jpeg_set_out_colorspace(zune_core::colorspace::ColorSpace::RGB);
            let mut dec = zune_jpeg::JpegDecoder::new_with_options(
                zune_core::bytestream::ZCursor::new(&bytes[..]),
                opts,
            );
            dec.decode().map(|p| (p, dec.info()))
        };
        let (pixels, info) = match decode(true) {
            Ok(r) => r,
            // stray bytes between markers, written by some cameras: decoded leniently
            Err(e) if format!("{e:?}").contains("Extra bytes between headers") => decode(false)
                .map_err(|e| Error::bad_input(path, format!("damaged or truncated JPEG: {e:?}")))?,
            Err(e) => {
                return Err(Error::bad_input(
                    path,
                    format!("damaged or truncated JPEG: {e:?}"),
                ));
            }
        };
        let info = info.ok_or_else(|| Error::bad_input(path, "JPEG without a frame header"))?;
        let (w, h) = (u32::from(info.width), u32::from(info.height));
        return image::RgbImage::from_raw(w, h, pixels).ok_or_else(|| {
            Error::bad_input(
                path,
                format!("JPEG decoded to the wrong number of bytes for {w} x {h}"),
            )
        });
    }
    image::load_from_memory_with_format(&bytes, format)
        .map(|i| i.to_rgb8())
        .map_err(|e| Error::bad_input(path, format!("cannot decode image: {e}")))
}

/// The EXIF orientation (1–8) of the image file at `path`: how its stored pixels turn into
/// the picture as viewers show it; 1 (as stored) without EXIF data, without the tag, or with
/// EXIF data that cannot be read.
pub fn exif_orientation(path: &Path) -> u8 {
    let Ok(file) = std::fs::File::open(path) else {
        return 1;
    };
    let Ok(data) = exif::Reader::new().read_from_container(&mut std::io::BufReader::new(file))
    else {
        return 1;
    };
    data.get_field(exif::Tag::Orientation, exif::In::PRIMARY)
        .and_then(|f| f.value.get_uint(0))
        .filter(|v| (1..=8).contains(v))
        .map_or(1, |v| v as u8)
}

/// A photo decoded as [`decode_rgb8`] and turned as its EXIF orientation says (a phone's
/// portrait photo stored sideways comes out upright), so that its pixels are those a
/// viewer shows and a camera or GCPs picked on it refer to.
pub fn decode_photo_rgb8(path: &Path) -> Result<image::RgbImage> {
    let img = decode_rgb8(path)?;
    match image::metadata::Orientation::from_exif(exif_orientation(path)) {
        Some(o) if o != image::metadata::Orientation::NoTransforms => {
            let mut d = image::DynamicImage::ImageRgb8(img);
            d.apply_orientation(o);
            Ok(d.to_rgb8())
        }
        _ => Ok(img),
    }
}

/// The size of a photo as [`decode_photo_rgb8`] gives it (the header's, its sides swapped
/// for EXIF orientations 5–8). Errors name the file.
pub fn photo_dimensions(path: &Path) -> Result<(u32, u32)> {
    if let Err(e) = std::fs::metadata(path) {
        return Err(Error::io(path, e));
    }
    let (w, h) = image::image_dimensions(path).map_err(|e| match e {
        image::ImageError::IoError(io) => Error::io(path, io),
        other => Error::bad_input(path, format!("cannot read image: {other}")),
    })?;
    Ok(if exif_orientation(path) >= 5 {
        (h, w)
    } else {
        (w, h)
    })
}
