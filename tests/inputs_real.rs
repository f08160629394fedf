//! Input readers on the shared real data (see /work/shared/data/real/README.md).
//! These tests fail (never skip) if the data is missing.

mod common;

use cliffmap::{DemLoadOptions, GridGeoref, OrthoPlacement, load_dem, load_ortho};
use common::real_data;

fn close(a: f32, b: f64, tol: f64) -> bool {
    (a as f64 - b).abs() <= tol
}

#[test]
fn engabreen_raw_f32_and_ortho_on_same_grid() {
    let p = real_data("engabreen/engabreen_dem_3m_507x590.f32");
    let opts = DemLoadOptions {
        width: Some(507),
        height: Some(590),
        spacing: Some(3.0),
        origin: Some((445302.17, 7396769.45)),
        ..Default::default()
    };
    let dem = load_dem(&p, &opts).unwrap();
    assert_eq!((dem.width, dem.height), (507, 590));
    assert_eq!(dem.georef, GridGeoref::new(445302.17, 7396769.45, 3.0));
    let (lo, hi) = dem.height_range();
    assert!(
        close(lo, 213.1, 0.05) && close(hi, 1078.3, 0.05),
        "range {lo}..{hi}"
    );
    assert_eq!(dem.void_fraction(), 0.0);
    // The format is inferred from the extension; without width/height it is refused.
    let e = load_dem(&p, &DemLoadOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("engabreen_dem_3m_507x590.f32") && e.contains("--width"),
        "{e}"
    );

    let op = real_data("engabreen/engabreen_ortho_3m_507x590.png");
    let o = load_ortho(&op, OrthoPlacement::SameGridAsDem, &dem, 1 << 30).unwrap();
    assert_eq!((o.image.width(), o.image.height()), (507, 590));
    assert_eq!(o.georef, dem.georef);
    // The black wedge (no image data in the source) is NOT turned into no-data automatically.
    let black = o
        .image
        .pixels()
        .filter(|p| p[0] == 0 && p[1] == 0 && p[2] == 0)
        .count();
    assert!(
        black > 1000,
        "expected the black wedge, found {black} black pixels"
    );
    assert!(o.image.pixels().all(|p| p[3] == 255));
    // The wedge is at the lower left.
    let corner = o.image.get_pixel(0, 589);
    assert_eq!([corner[0], corner[1], corner[2]], [0, 0, 0]);
}

#[test]
fn st_helens_png16() {
    let p = real_data("argudo_glaciers/sthelens_10m.png");
    let opts = DemLoadOptions {
        z_scale: Some(0.1),
        spacing: Some(10.0),
        ..Default::default()
    };
    let dem = load_dem(&p, &opts).unwrap();
    assert_eq!((dem.width, dem.height), (2000, 2000));
    assert_eq!(dem.georef.spacing_x, 10.0);
    let (lo, hi) = dem.height_range();
    assert!(
        close(lo, 567.5, 0.05) && close(hi, 2538.2, 0.05),
        "range {lo}..{hi}"
    );
    // Heights are multiples of a decimetre.
    assert!(
        dem.heights
            .iter()
            .step_by(997)
            .all(|&h| ((h as f64 * 10.0) - (h as f64 * 10.0).round()).abs() < 1e-3)
    );
}

#[test]
fn grand_canyon_terrain_rgb_tiles() {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for t in ["12-758-1608", "12-758-1609", "12-759-1608", "12-759-1609"] {
        let p = real_data(&format!("grand_canyon_tiles/{t}.terrain.png"));
        let dem = load_dem(
            &p,
            &DemLoadOptions {
                spacing: Some(30.9),
                ..Default::default()
            },
        )
        .unwrap();
        assert_eq!((dem.width, dem.height), (256, 256));
        assert_eq!(dem.void_fraction(), 0.0);
        let (a, b) = dem.height_range();
        // README gives the range rounded to whole metres: 439..2184.
        assert!(a >= 438.5 && b < 2184.5, "{t}: {a}..{b}");
        lo = lo.min(a);
        hi = hi.max(b);
    }
    // The README's range for the whole block.
    assert!(
        close(lo, 439.0, 0.5) && close(hi, 2184.0, 0.5),
        "block range {lo}..{hi}"
    );
}

#[test]
fn fuji_terrain_rgb() {
    let p = real_data("misc/fuji_terrain_rgb_z10_906_404.png");
    let dem = load_dem(
        &p,
        &DemLoadOptions {
            spacing: Some(62.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!((dem.width, dem.height), (512, 512));
    let (lo, hi) = dem.height_range();
    assert!(
        close(lo, 13.7, 0.05) && close(hi, 3751.0, 0.5),
        "range {lo}..{hi}"
    );
    let imax = dem
        .heights
        .iter()
        .enumerate()
        .fold(0, |m, (i, &h)| if h > dem.heights[m] { i } else { m });
    let (row, col) = (imax / dem.width, imax % dem.width);
    // README: "the maximum sits at pixel (308,178)" — written as (x, y): column 308, row 178.
    assert_eq!((col, row), (308, 178));
}

#[test]
fn exploradores_aster_geotiff() {
    let p = real_data("misc/exploradores_aster_dem_30m_utm18s.tif");
    let dem = load_dem(&p, &DemLoadOptions::default()).unwrap();
    assert_eq!((dem.width, dem.height), (539, 618));
    // Tags: ModelPixelScale (30, 30), tiepoint (0,0) -> (627175, 4852085), PixelIsArea,
    // so the first sample centre is half a pixel in.
    assert_eq!(dem.georef, GridGeoref::new(627190.0, 4852070.0, 30.0));
    assert_eq!(dem.crs.as_deref(), Some("EPSG:32718"));
    let vf = dem.void_fraction();
    assert!((0.025..0.029).contains(&vf), "void fraction {vf}");
    let valid: Vec<f32> = dem
        .heights
        .iter()
        .zip(&dem.void)
        .filter(|(_, v)| !**v)
        .map(|(h, _)| *h)
        .collect();
    let (vlo, vhi) = valid
        .iter()
        .fold((f32::MAX, f32::MIN), |(a, b), &h| (a.min(h), b.max(h)));
    eprintln!(
        "exploradores: voids {:.3} %, valid heights {vlo}..{vhi}",
        vf * 100.0
    );
    assert!(vlo > -100.0 && vhi < 5000.0, "valid range {vlo}..{vhi}");
    assert!(
        dem.heights
            .iter()
            .all(|h| h.is_finite() && *h >= vlo && *h <= vhi)
    );
    // With the no-data value overridden to something absent, -9999 is kept as a height,
    // so the voids are visible as the minimum.
    let raw = load_dem(
        &p,
        &DemLoadOptions {
            nodata: Some(-12345.0),
            ..Default::default()
        },
    )
    .unwrap();
    assert_eq!(raw.height_range().0, -9999.0);
}
