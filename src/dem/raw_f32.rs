//! Raw little-endian f32 reader: `width * height` values, row-major, row 0 = north.
//! The file carries no georeference; size must be exactly `width * height * 4` bytes.

use std::fs::File;
use std::io::Read;
use std::path::Path;

use super::convert;
use super::{Decoded, DemLoadOptions, limits};
use crate::error::{Error, Result};

/// Reads a raw f32 DEM. `opts.width` and `opts.height` are required.
pub(crate) fn read(path: &Path, opts: &DemLoadOptions) -> Result<Decoded> {
    let (Some(w), Some(h)) = (opts.width, opts.height) else {
        return Err(Error::bad_input(
            path,
            "raw f32 DEM needs its size: pass --width and --height (in samples)",
        ));
    };
    let len = std::fs::metadata(path)
        .map_err(|e| Error::io(path, e))?
        .len();
    let expected = (w as u64)
        .checked_mul(h as u64)
        .and_then(|n| n.checked_mul(4));
    if expected != Some(len) {
        let hint = if len % 4 == 0 && w > 0 && (len / 4) % w as u64 == 0 {
            format!(
                " (with width {w} the file holds {} rows)",
                len / 4 / w as u64
            )
        } else {
            String::new()
        };
        return Err(Error::bad_input(
            path,
            format!(
                "raw f32 file has {len} bytes but {w}x{h} samples need {} bytes{hint}",
                expected.map_or("more than 2^64".to_string(), |e| e.to_string())
            ),
        ));
    }
    super::check_size(path, w, h)?;
    limits::check(
        path,
        w as u64,
        h as u64,
        4 + limits::DEM_BYTES_PER_SAMPLE,
        opts.max_memory,
    )?;
    let mut bytes = Vec::with_capacity(len as usize);
    File::open(path)
        .and_then(|f| f.take(len).read_to_end(&mut bytes))
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 != len {
        return Err(Error::bad_input(path, "file shrank while being read"));
    }
    let rule = convert::VoidRule::new(opts.nodata, opts.nodata_sentinels);
    let mut sentinels = convert::SentinelCounts::default();
    let value = |i: usize| {
        f32::from_le_bytes([
            bytes[4 * i],
            bytes[4 * i + 1],
            bytes[4 * i + 2],
            bytes[4 * i + 3],
        ])
    };
    let (heights, void) =
        convert::to_heights(path, w, w * h, super::scaling(opts), rule.declared(), |i| {
            let v = value(i);
            (v as f64, sentinels.note(rule, rule.matches(v)))
        })?;
    Ok(Decoded {
        sentinels,
        width: w,
        height: h,
        heights,
        void,
        georef: None,
        crs: None,
        geographic: false,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::load_dem;
    use crate::georef::GridGeoref;

    fn write(path: &Path, v: &[f32]) {
        std::fs::write(
            path,
            v.iter().flat_map(|x| x.to_le_bytes()).collect::<Vec<u8>>(),
        )
        .unwrap();
    }

    #[test]
    fn round_trip_with_georef_and_nodata() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("dem.f32");
        let vals: Vec<f32> = (0..12).map(|i| 100.0 + i as f32 * 0.25).collect();
        write(&p, &vals);
        let opts = DemLoadOptions {
            width: Some(4),
            height: Some(3),
            spacing: Some(3.0),
            origin: Some((445302.17, 7396769.45)),
            ..Default::default()
        };
        let dem = load_dem(&p, &opts).unwrap();
        assert_eq!((dem.width, dem.height), (4, 3));
        assert_eq!(dem.heights, vals);
        assert_eq!(dem.georef, GridGeoref::new(445302.17, 7396769.45, 3.0));
        assert!(dem.void.iter().all(|v| !v));

        let mut v2 = vals.clone();
        v2[5] = -9999.0;
        v2[6] = f32::NAN;
        write(&p, &v2);
        // undeclared, both are common no-data markers: voids
        let dem = load_dem(&p, &opts).unwrap();
        assert!(dem.void[5] && dem.void[6] && dem.void.iter().filter(|v| **v).count() == 2);
        // without the markers the NaN is an error naming its place
        let opts = DemLoadOptions {
            nodata_sentinels: false,
            ..opts
        };
        let e = load_dem(&p, &opts).unwrap_err().to_string();
        assert!(
            e.contains("dem.f32") && e.contains("row 1, column 2") && e.contains("--nodata"),
            "{e}"
        );
        // NaN declared: sample 6 is a void filled from its neighbours; -9999 is a (plausible) height.
        let dem = load_dem(
            &p,
            &DemLoadOptions {
                nodata: Some(f64::NAN),
                ..opts.clone()
            },
        )
        .unwrap();
        assert!(dem.void[6] && dem.void.iter().filter(|v| **v).count() == 1);
        assert_eq!(dem.heights[5], -9999.0);
        let nbrs = [1usize, 2, 3, 5, 7, 9, 10, 11];
        let mean = nbrs.iter().map(|&i| v2[i] as f64).sum::<f64>() / 8.0;
        assert_eq!(dem.heights[6], mean as f32);
        // -9999 declared: the undeclared NaN is an error.
        let e = load_dem(
            &p,
            &DemLoadOptions {
                nodata: Some(-9999.0),
                ..opts.clone()
            },
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("row 1, column 2") && e.contains("NaN"), "{e}");
    }
}
