//! Bad inputs: every case must give `Err` (never panic) whose message names the file.

mod common;

use std::path::{Path, PathBuf};

use cliffmap::{
    DemFormat, DemLoadOptions, Error, GridGeoref, OrthoPlacement, WorldRect, load_dem, load_ortho,
};
use common::tiffgen::{self, Geo, Raw};
use image::{ImageBuffer, Luma, Rgb};
use tiff::encoder::{Compression, colortype};
use tiff::tags::Predictor;

/// Asserts `r` is an error whose message contains the file name and every `words`.
fn bad<T: std::fmt::Debug>(r: cliffmap::Result<T>, path: &Path, words: &[&str]) -> Error {
    let e = r.expect_err("bad input was accepted");
    let msg = e.to_string();
    eprintln!("{msg}");
    let name = path.file_name().unwrap().to_str().unwrap();
    assert!(msg.contains(name), "message does not name {name}: {msg}");
    for w in words {
        assert!(msg.contains(w), "message lacks {w:?}: {msg}");
    }
    e
}

fn raw_opts(w: usize, h: usize) -> DemLoadOptions {
    DemLoadOptions {
        width: Some(w),
        height: Some(h),
        ..Default::default()
    }
}

fn write_f32(path: &Path, v: &[f32]) {
    std::fs::write(
        path,
        v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(),
    )
    .unwrap();
}

fn grid(w: usize, h: usize) -> Vec<f32> {
    (0..w * h).map(|i| 100.0 + i as f32).collect()
}

fn geo() -> Geo {
    Geo {
        scale: (10.0, 10.0),
        tie: (0.0, 0.0, 500000.0, 6000000.0),
        pixel_is_point: false,
        epsg: Some(32633),
        nodata: None,
    }
}

fn truncate(path: &Path, keep: usize) -> PathBuf {
    let b = std::fs::read(path).unwrap();
    let out = path.with_file_name(format!(
        "trunc_{}",
        path.file_name().unwrap().to_str().unwrap()
    ));
    std::fs::write(&out, &b[..keep.min(b.len())]).unwrap();
    out
}

/// A PNG whose IHDR claims `w x h` 16-bit grey, followed by a tiny IDAT and IEND.
fn png_header_only(path: &Path, w: u32, h: u32) {
    let mut out = vec![0x89, b'P', b'N', b'G', b'\r', b'\n', 0x1a, b'\n'];
    let mut chunk = |ty: &[u8; 4], data: &[u8]| {
        out.extend_from_slice(&(data.len() as u32).to_be_bytes());
        let mut c = ty.to_vec();
        c.extend_from_slice(data);
        out.extend_from_slice(&c);
        out.extend_from_slice(&crc32fast::hash(&c).to_be_bytes());
    };
    let mut ihdr = Vec::new();
    ihdr.extend_from_slice(&w.to_be_bytes());
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[16, 0, 0, 0, 0]);
    chunk(b"IHDR", &ihdr);
    chunk(b"IDAT", &[0x78, 0x9c, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01]);
    chunk(b"IEND", &[]);
    std::fs::write(path, out).unwrap();
}

#[test]
fn missing_file() {
    let p = PathBuf::from("/nonexistent/dir/nothere.tif");
    let e = bad(load_dem(&p, &Default::default()), &p, &[]);
    assert!(matches!(e, Error::Io { .. }));
}

#[test]
fn raw_f32_wrong_size_missing_dims_and_tiny() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("short.f32");
    write_f32(&p, &grid(10, 9)); // one row short of 10x10
    bad(
        load_dem(&p, &raw_opts(10, 10)),
        &p,
        &["360 bytes", "400 bytes", "9 rows"],
    );
    bad(
        load_dem(&p, &DemLoadOptions::default()),
        &p,
        &["--width", "--height"],
    );
    bad(load_dem(&p, &raw_opts(0, 10)), &p, &["--width"]);
    // overflowing size claim
    bad(load_dem(&p, &raw_opts(usize::MAX / 2, 8)), &p, &["bytes"]);
    // smaller than 2x2
    let p1 = d.path().join("row.f32");
    write_f32(&p1, &grid(5, 1));
    bad(load_dem(&p1, &raw_opts(5, 1)), &p1, &["2x2"]);
}

#[test]
fn undeclared_nan_inf_and_absurd_heights() {
    let d = tempfile::tempdir().unwrap();
    let (w, h) = (6usize, 5usize);
    for (name, val, words) in [
        (
            "nan.f32",
            f32::NAN,
            &["row 3, column 4", "--nodata nan"][..],
        ),
        (
            "inf.f32",
            f32::INFINITY,
            &["row 3, column 4", "--nodata"][..],
        ),
        (
            "huge.f32",
            3.0e6,
            &["row 3, column 4", "--nodata", "--z-scale"][..],
        ),
        ("fmin.f32", f32::MIN, &["row 3, column 4", "--nodata"][..]),
    ] {
        let mut v = grid(w, h);
        v[3 * w + 4] = val;
        let p = d.path().join(name);
        write_f32(&p, &v);
        // (NaN and the lowest f32 are no-data markers by default: tests/real_photos.rs)
        let opts = DemLoadOptions {
            nodata_sentinels: false,
            ..raw_opts(w, h)
        };
        bad(load_dem(&p, &opts), &p, words);
    }
    // same in a GeoTIFF
    let mut v = grid(w, h);
    v[w + 2] = f32::NAN;
    let p = d.path().join("nan.tif");
    tiffgen::write_strips::<colortype::Gray32Float>(
        &p,
        w as u32,
        h as u32,
        &v,
        Compression::Lzw,
        Predictor::None,
        Some(&geo()),
    );
    let no_sentinels = DemLoadOptions {
        nodata_sentinels: false,
        ..Default::default()
    };
    bad(
        load_dem(&p, &no_sentinels),
        &p,
        &["row 1, column 2", "--nodata nan"],
    );
    // a z-scale that makes heights absurd
    let p = d.path().join("scaled.tif");
    tiffgen::write_strips::<colortype::Gray32Float>(
        &p,
        w as u32,
        h as u32,
        &grid(w, h),
        Compression::Lzw,
        Predictor::None,
        Some(&geo()),
    );
    bad(
        load_dem(
            &p,
            &DemLoadOptions {
                z_scale: Some(1000.0),
                ..Default::default()
            },
        ),
        &p,
        &["implausible", "--z-scale"],
    );
}

#[test]
fn all_nodata() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("void.tif");
    let v = vec![-9999.0f32; 16];
    tiffgen::write_strips::<colortype::Gray32Float>(
        &p,
        4,
        4,
        &v,
        Compression::Uncompressed,
        Predictor::None,
        Some(&Geo {
            nodata: Some("-9999".into()),
            ..geo()
        }),
    );
    bad(load_dem(&p, &Default::default()), &p, &["no-data"]);
    let r = d.path().join("void.f32");
    write_f32(&r, &[f32::NAN; 9]);
    bad(
        load_dem(
            &r,
            &DemLoadOptions {
                nodata: Some(f64::NAN),
                ..raw_opts(3, 3)
            },
        ),
        &r,
        &["no-data"],
    );
}

#[test]
fn bad_options_name_the_file() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("ok.f32");
    write_f32(&p, &grid(3, 3));
    for s in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        bad(
            load_dem(
                &p,
                &DemLoadOptions {
                    spacing: Some(s),
                    ..raw_opts(3, 3)
                },
            ),
            &p,
            &["--spacing"],
        );
    }
    bad(
        load_dem(
            &p,
            &DemLoadOptions {
                origin: Some((f64::NAN, 0.0)),
                ..raw_opts(3, 3)
            },
        ),
        &p,
        &["--origin"],
    );
    bad(
        load_dem(
            &p,
            &DemLoadOptions {
                z_scale: Some(0.0),
                ..raw_opts(3, 3)
            },
        ),
        &p,
        &["--z-scale"],
    );
    bad(
        load_dem(
            &p,
            &DemLoadOptions {
                z_offset: Some(f64::NAN),
                ..raw_opts(3, 3)
            },
        ),
        &p,
        &["--z-offset"],
    );
}

#[test]
fn bad_geotiff_georeference() {
    let d = tempfile::tempdir().unwrap();
    for (name, scale) in [
        ("zero.tif", (0.0, 10.0)),
        ("neg.tif", (10.0, -10.0)),
        ("nanscale.tif", (f64::NAN, 10.0)),
    ] {
        let p = d.path().join(name);
        let g = Geo { scale, ..geo() };
        tiffgen::write_strips::<colortype::Gray32Float>(
            &p,
            3,
            3,
            &grid(3, 3),
            Compression::Uncompressed,
            Predictor::None,
            Some(&g),
        );
        bad(load_dem(&p, &Default::default()), &p, &["GeoTIFF"]);
    }
}

#[test]
fn huge_headers_are_refused_before_decoding() {
    let d = tempfile::tempdir().unwrap();
    // TIFF claiming 100000 x 100000 f32 with almost no data.
    let p = d.path().join("huge.tif");
    let raw = Raw {
        width: 100_000,
        height: 100_000,
        bits: 32,
        sample_format: 3,
        samples: 1,
        photometric: 1,
        tile: None,
        extra_alpha: false,
    };
    tiffgen::write_raw(&p, &raw, &[0u8; 64], None, false);
    let e = bad(load_dem(&p, &Default::default()), &p, &["--max-memory"]);
    assert!(matches!(e, Error::TooLarge { .. }), "{e}");
    // PNG claiming 60000 x 60000 16-bit grey.
    let q = d.path().join("huge.png");
    png_header_only(&q, 60_000, 60_000);
    let e = bad(
        load_dem(
            &q,
            &DemLoadOptions {
                max_memory: 1 << 30,
                ..Default::default()
            },
        ),
        &q,
        &["--max-memory"],
    );
    assert!(matches!(e, Error::TooLarge { .. }), "{e}");
    // A normal file over a small limit.
    let r = d.path().join("small.tif");
    tiffgen::write_strips::<colortype::Gray32Float>(
        &r,
        10,
        10,
        &grid(10, 10),
        Compression::Uncompressed,
        Predictor::None,
        Some(&geo()),
    );
    let e = bad(
        load_dem(
            &r,
            &DemLoadOptions {
                max_memory: 500,
                ..Default::default()
            },
        ),
        &r,
        &[],
    );
    assert!(
        matches!(
            e,
            Error::TooLarge {
                needed: 900,
                limit: 500,
                ..
            }
        ),
        "{e}"
    );
    // Raw f32 over the limit.
    let f = d.path().join("lim.f32");
    write_f32(&f, &grid(10, 10));
    let e = bad(
        load_dem(
            &f,
            &DemLoadOptions {
                max_memory: 100,
                ..raw_opts(10, 10)
            },
        ),
        &f,
        &[],
    );
    assert!(matches!(e, Error::TooLarge { .. }));
}

#[test]
fn zero_and_tiny_dimensions() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("zero.tif");
    let raw = Raw {
        width: 0,
        height: 5,
        bits: 32,
        sample_format: 3,
        samples: 1,
        photometric: 1,
        tile: None,
        extra_alpha: false,
    };
    tiffgen::write_raw(&p, &raw, &[0u8; 4], None, false);
    bad(load_dem(&p, &Default::default()), &p, &[]);
    let q = d.path().join("zero.png");
    png_header_only(&q, 0, 10);
    bad(load_dem(&q, &Default::default()), &q, &[]);
    let one = d.path().join("one.png");
    ImageBuffer::<Luma<u16>, Vec<u16>>::from_pixel(1, 1, Luma([5]))
        .save(&one)
        .unwrap();
    bad(load_dem(&one, &Default::default()), &one, &["2x2"]);
    let t = d.path().join("one_row.tif");
    tiffgen::write_strips::<colortype::Gray32Float>(
        &t,
        7,
        1,
        &grid(7, 1),
        Compression::Uncompressed,
        Predictor::None,
        None,
    );
    bad(load_dem(&t, &Default::default()), &t, &["2x2"]);
}

#[test]
fn truncated_and_corrupt_files() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path().join("full.tif");
    let (w, h) = (40u32, 30u32);
    tiffgen::write_strips::<colortype::Gray32Float>(
        &p,
        w,
        h,
        &grid(w as usize, h as usize),
        Compression::Deflate(Default::default()),
        Predictor::None,
        Some(&geo()),
    );
    let len = std::fs::metadata(&p).unwrap().len() as usize;
    for keep in [0, 3, 8, 100, len / 2, len - 10] {
        let t = truncate(&p, keep);
        bad(load_dem(&t, &Default::default()), &t, &[]);
    }
    // strip offset pointing past the end of the file
    let c = d.path().join("liar.tif");
    let raw = Raw {
        width: 4,
        height: 4,
        bits: 32,
        sample_format: 3,
        samples: 1,
        photometric: 1,
        tile: None,
        extra_alpha: false,
    };
    tiffgen::write_raw(&c, &raw, &tiffgen::f32_bytes(&grid(4, 4)), None, true);
    bad(load_dem(&c, &Default::default()), &c, &[]);
    // not a TIFF at all
    let j = d.path().join("junk.tif");
    std::fs::write(&j, b"this is not a tiff file").unwrap();
    bad(load_dem(&j, &Default::default()), &j, &["TIFF"]);

    let png = d.path().join("dem16.png");
    ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(64, 64, |x, y| Luma([(x * 977 + y * 131) as u16]))
        .save(&png)
        .unwrap();
    let plen = std::fs::metadata(&png).unwrap().len() as usize;
    for keep in [0, 20, 40, plen / 2, plen - 5] {
        let t = truncate(&png, keep);
        bad(load_dem(&t, &Default::default()), &t, &[]);
        bad(
            load_dem(
                &t,
                &DemLoadOptions {
                    format: Some(DemFormat::Png16),
                    ..Default::default()
                },
            ),
            &t,
            &[],
        );
        bad(
            load_dem(
                &t,
                &DemLoadOptions {
                    format: Some(DemFormat::TerrainRgb),
                    ..Default::default()
                },
            ),
            &t,
            &[],
        );
    }
}

#[test]
fn unsupported_sample_formats() {
    let d = tempfile::tempdir().unwrap();
    // complex float (SampleFormat 6, 64 bits per sample)
    let p = d.path().join("complex.tif");
    let raw = Raw {
        width: 4,
        height: 4,
        bits: 64,
        sample_format: 6,
        samples: 1,
        photometric: 1,
        tile: None,
        extra_alpha: false,
    };
    tiffgen::write_raw(&p, &raw, &[0u8; 128], None, false);
    bad(load_dem(&p, &Default::default()), &p, &[]);
    // 1-bit
    let b = d.path().join("bilevel.tif");
    let raw = Raw {
        width: 16,
        height: 4,
        bits: 1,
        sample_format: 1,
        samples: 1,
        photometric: 1,
        tile: None,
        extra_alpha: false,
    };
    tiffgen::write_raw(&b, &raw, &[0xAAu8; 8], None, false);
    bad(load_dem(&b, &Default::default()), &b, &["1-bit"]);
    // RGB is not a DEM
    let c = d.path().join("rgb.tif");
    tiffgen::write_strips::<colortype::RGB8>(
        &c,
        3,
        3,
        &[7u8; 27],
        Compression::Uncompressed,
        Predictor::None,
        None,
    );
    bad(load_dem(&c, &Default::default()), &c, &[]);
    // 8-bit grey PNG without an explicit format
    let g = d.path().join("grey8.png");
    ImageBuffer::<Luma<u8>, Vec<u8>>::from_pixel(4, 4, Luma([3]))
        .save(&g)
        .unwrap();
    bad(
        load_dem(&g, &Default::default()),
        &g,
        &["--dem-format png16"],
    );
    // RGB PNG read as png16
    let r = d.path().join("rgb.png");
    ImageBuffer::<Rgb<u8>, Vec<u8>>::from_pixel(4, 4, Rgb([1, 2, 3]))
        .save(&r)
        .unwrap();
    bad(
        load_dem(
            &r,
            &DemLoadOptions {
                format: Some(DemFormat::Png16),
                ..Default::default()
            },
        ),
        &r,
        &["terrain-rgb"],
    );
    // unknown extension, unknown content
    let u = d.path().join("mystery.xyz");
    std::fs::write(&u, [1u8, 2, 3, 4, 5, 6, 7, 8, 9]).unwrap();
    bad(load_dem(&u, &Default::default()), &u, &["--dem-format"]);
}

#[test]
fn bad_orthos() {
    let d = tempfile::tempdir().unwrap();
    let dem = cliffmap::Dem::from_heights(4, 4, vec![1.0; 16], GridGeoref::new(100.0, 200.0, 2.0))
        .unwrap();
    let p = d.path().join("photo.png");
    ImageBuffer::<Rgb<u8>, Vec<u8>>::from_pixel(5, 4, Rgb([9, 9, 9]))
        .save(&p)
        .unwrap();
    bad(
        load_ortho(&p, OrthoPlacement::FromFile, &dem, 1 << 20),
        &p,
        &["--ortho-same-grid"],
    );
    bad(
        load_ortho(&p, OrthoPlacement::SameGridAsDem, &dem, 1 << 20),
        &p,
        &["5x4", "4x4"],
    );
    let far = WorldRect {
        min_x: 1e6,
        min_y: 1e6,
        max_x: 1e6 + 10.0,
        max_y: 1e6 + 10.0,
    };
    bad(
        load_ortho(&p, OrthoPlacement::Extent(far), &dem, 1 << 20),
        &p,
        &["overlap"],
    );
    let nan = WorldRect {
        min_x: f64::NAN,
        min_y: 0.0,
        max_x: 1.0,
        max_y: 1.0,
    };
    bad(
        load_ortho(&p, OrthoPlacement::Extent(nan), &dem, 1 << 20),
        &p,
        &["--ortho-extent"],
    );
    let e = bad(
        load_ortho(&p, OrthoPlacement::SameGridAsDem, &dem, 10),
        &p,
        &[],
    );
    assert!(matches!(e, Error::TooLarge { .. }));
    let len = std::fs::metadata(&p).unwrap().len() as usize;
    for keep in [0, 30, len / 2] {
        let t = truncate(&p, keep);
        bad(
            load_ortho(&t, OrthoPlacement::SameGridAsDem, &dem, 1 << 20),
            &t,
            &[],
        );
    }
    // a 16-bit-per-sample TIFF ortho and a GeoTIFF outside the DEM
    let t16 = d.path().join("rgb16.tif");
    tiffgen::write_strips::<colortype::RGB16>(
        &t16,
        4,
        4,
        &[300u16; 48],
        Compression::Uncompressed,
        Predictor::None,
        Some(&geo()),
    );
    bad(
        load_ortho(&t16, OrthoPlacement::FromFile, &dem, 1 << 20),
        &t16,
        &["8-bit"],
    );
    let t8 = d.path().join("rgb8.tif");
    tiffgen::write_strips::<colortype::RGB8>(
        &t8,
        4,
        4,
        &[30u8; 48],
        Compression::Uncompressed,
        Predictor::None,
        Some(&geo()),
    );
    bad(
        load_ortho(&t8, OrthoPlacement::FromFile, &dem, 1 << 20),
        &t8,
        &["overlap"],
    );
}

mod corrupted_bytes {
    use super::*;
    use proptest::prelude::*;

    fn check_no_panic(bytes: &[u8], name: &str, edits: &[(usize, u8)]) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(name);
        let mut b = bytes.to_vec();
        for &(pos, val) in edits {
            let n = b.len();
            b[pos % n] = val;
        }
        std::fs::write(&p, &b).unwrap();
        let opts = DemLoadOptions {
            max_memory: 1 << 22,
            ..Default::default()
        };
        match load_dem(&p, &opts) {
            Ok(dem) => {
                assert_eq!(dem.heights.len(), dem.width * dem.height);
                assert!(dem.heights.iter().all(|h| h.is_finite()));
            }
            Err(e) => assert!(e.to_string().contains(name), "{e}"),
        }
    }

    fn sample_tiff() -> Vec<u8> {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("s.tif");
        let g = Geo {
            nodata: Some("-9999".into()),
            ..geo()
        };
        tiffgen::write_strips::<colortype::Gray32Float>(
            &p,
            12,
            10,
            &grid(12, 10),
            Compression::Lzw,
            Predictor::None,
            Some(&g),
        );
        std::fs::read(&p).unwrap()
    }

    fn sample_png() -> Vec<u8> {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("s.png");
        ImageBuffer::<Luma<u16>, Vec<u16>>::from_fn(12, 10, |x, y| Luma([(x * 300 + y) as u16]))
            .save(&p)
            .unwrap();
        std::fs::read(&p).unwrap()
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]
        #[test]
        fn mutated_tiff_never_panics(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6)) {
            check_no_panic(&sample_tiff(), "mut.tif", &edits);
        }
        #[test]
        fn mutated_png_never_panics(edits in proptest::collection::vec((any::<usize>(), any::<u8>()), 1..6)) {
            check_no_panic(&sample_png(), "mut.png", &edits);
        }
    }
}
