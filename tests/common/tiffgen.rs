//! Test-only GeoTIFF writers: strips through the `tiff` crate's encoder (with its
//! compression and predictor), and a hand-assembled directory for tiles and odd sample
//! types the encoder cannot produce. Shared by unit tests (via `#[path]`) and integration
//! tests. Panics on I/O errors (test helper).
#![allow(dead_code)]

use std::fs::File;
use std::io::BufWriter;
use std::path::Path;

use tiff::encoder::colortype::ColorType;
use tiff::encoder::{Compression, TiffEncoder, TiffValue};
use tiff::tags::{Predictor, Tag};

/// GeoTIFF tags to write.
#[derive(Clone, Debug)]
pub struct Geo {
    /// ModelPixelScale (x, y).
    pub scale: (f64, f64),
    /// ModelTiepoint: raster (i, j) -> model (x, y).
    pub tie: (f64, f64, f64, f64),
    /// GTRasterTypeGeoKey = PixelIsPoint (else PixelIsArea).
    pub pixel_is_point: bool,
    /// ProjectedCSTypeGeoKey.
    pub epsg: Option<u16>,
    /// GDAL_NODATA string.
    pub nodata: Option<String>,
}

fn write_geo<W: std::io::Write + std::io::Seek, K: tiff::encoder::TiffKind>(
    dir: &mut tiff::encoder::DirectoryEncoder<'_, W, K>,
    geo: &Geo,
) {
    dir.write_tag(
        Tag::ModelPixelScaleTag,
        &[geo.scale.0, geo.scale.1, 0.0][..],
    )
    .unwrap();
    dir.write_tag(
        Tag::ModelTiepointTag,
        &[geo.tie.0, geo.tie.1, 0.0, geo.tie.2, geo.tie.3, 0.0][..],
    )
    .unwrap();
    let mut keys: Vec<u16> = vec![
        1,
        1,
        0,
        0,
        1024,
        0,
        1,
        1,
        1025,
        0,
        1,
        if geo.pixel_is_point { 2 } else { 1 },
    ];
    if let Some(e) = geo.epsg {
        keys.extend_from_slice(&[3072, 0, 1, e]);
    }
    keys[3] = (keys.len() / 4 - 1) as u16;
    dir.write_tag(Tag::GeoKeyDirectoryTag, &keys[..]).unwrap();
    if let Some(nd) = &geo.nodata {
        dir.write_tag(Tag::GdalNodata, nd.as_str()).unwrap();
    }
}

/// Writes a striped TIFF with the encoder's compression/predictor and optional geo tags.
pub fn write_strips<C: ColorType>(
    path: &Path,
    w: u32,
    h: u32,
    data: &[C::Inner],
    compression: Compression,
    predictor: Predictor,
    geo: Option<&Geo>,
) where
    [C::Inner]: TiffValue,
{
    let f = BufWriter::new(File::create(path).unwrap());
    let mut enc = TiffEncoder::new(f)
        .unwrap()
        .with_compression(compression)
        .with_predictor(predictor);
    let mut img = enc.new_image::<C>(w, h).unwrap();
    img.rows_per_strip(3).unwrap();
    if let Some(g) = geo {
        write_geo(img.encoder(), g);
    }
    img.write_data(data).unwrap();
}

/// Layout of a hand-assembled, uncompressed TIFF.
#[derive(Clone, Debug)]
pub struct Raw {
    pub width: u32,
    pub height: u32,
    pub bits: u16,
    /// 1 uint, 2 int, 3 float, 6 complex float...
    pub sample_format: u16,
    pub samples: u16,
    /// 1 BlackIsZero, 2 RGB.
    pub photometric: u16,
    /// Some((tile_w, tile_h)) for tiles, None for one strip.
    pub tile: Option<(u32, u32)>,
    /// ExtraSamples value for a 4th sample (2 = unassociated alpha).
    pub extra_alpha: bool,
}

/// Writes `bytes` (row-major, pixel-interleaved, native endian, rows of
/// `ceil(width*samples*bits/8)` bytes) as a TIFF laid out per `raw`. If `lie_offset` the
/// data offset points past the end of the file (a corrupt file).
pub fn write_raw(path: &Path, raw: &Raw, bytes: &[u8], geo: Option<&Geo>, lie_offset: bool) {
    let f = BufWriter::new(File::create(path).unwrap());
    let mut enc = TiffEncoder::new(f).unwrap();
    let mut dir = enc.image_directory().unwrap();
    let row_bytes = (raw.width as usize * raw.samples as usize * raw.bits as usize).div_ceil(8);
    let (mut offsets, mut counts): (Vec<u32>, Vec<u32>) = (vec![], vec![]);
    match raw.tile {
        None => {
            let off = dir.write_data(bytes).unwrap();
            offsets.push(if lie_offset { 1 << 30 } else { off as u32 });
            counts.push(bytes.len() as u32);
        }
        Some((tw, th)) => {
            let px = raw.samples as usize * raw.bits as usize / 8;
            for ty in 0..raw.height.div_ceil(th) {
                for tx in 0..raw.width.div_ceil(tw) {
                    let mut tile = vec![0u8; tw as usize * th as usize * px];
                    for r in 0..th {
                        let y = ty * th + r;
                        if y >= raw.height {
                            break;
                        }
                        for c in 0..tw {
                            let x = tx * tw + c;
                            if x >= raw.width {
                                break;
                            }
                            let src = y as usize * row_bytes + x as usize * px;
                            let dst = (r * tw + c) as usize * px;
                            tile[dst..dst + px].copy_from_slice(&bytes[src..src + px]);
                        }
                    }
                    let off = dir.write_data(&tile[..]).unwrap();
                    offsets.push(off as u32);
                    counts.push(tile.len() as u32);
                }
            }
        }
    }
    dir.write_tag(Tag::ImageWidth, raw.width).unwrap();
    dir.write_tag(Tag::ImageLength, raw.height).unwrap();
    dir.write_tag(
        Tag::BitsPerSample,
        &vec![raw.bits; raw.samples as usize][..],
    )
    .unwrap();
    dir.write_tag(Tag::Compression, 1u16).unwrap();
    dir.write_tag(Tag::PhotometricInterpretation, raw.photometric)
        .unwrap();
    dir.write_tag(Tag::SamplesPerPixel, raw.samples).unwrap();
    dir.write_tag(
        Tag::SampleFormat,
        &vec![raw.sample_format; raw.samples as usize][..],
    )
    .unwrap();
    if raw.extra_alpha {
        dir.write_tag(Tag::ExtraSamples, &[2u16][..]).unwrap();
    }
    match raw.tile {
        None => {
            dir.write_tag(Tag::RowsPerStrip, raw.height).unwrap();
            dir.write_tag(Tag::StripOffsets, &offsets[..]).unwrap();
            dir.write_tag(Tag::StripByteCounts, &counts[..]).unwrap();
        }
        Some((tw, th)) => {
            dir.write_tag(Tag::TileWidth, tw).unwrap();
            dir.write_tag(Tag::TileLength, th).unwrap();
            dir.write_tag(Tag::TileOffsets, &offsets[..]).unwrap();
            dir.write_tag(Tag::TileByteCounts, &counts[..]).unwrap();
        }
    }
    if let Some(g) = geo {
        write_geo(&mut dir, g);
    }
    dir.finish().unwrap();
}

/// Native-endian bytes of f32 samples.
pub fn f32_bytes(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_ne_bytes()).collect()
}
