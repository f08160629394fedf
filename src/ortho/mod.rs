//! Stage 0 input: the orthophoto.
//!
//! Data type: [`Ortho`], an RGBA8 image (alpha 0 = no coverage, 255 = known colour) with
//! an f64 [`GridGeoref`] for its pixel centres, north-up. Readers: PNG, JPEG and GeoTIFF
//! (RGB/RGBA/grey, 8-bit), placed by GeoTIFF tags, by an explicit extent, or on the DEM's
//! grid ([`OrthoPlacement`]). Pure black is ordinary colour; only alpha 0 (or a GeoTIFF's
//! GDAL_NODATA colour) marks pixels without data.

mod placement;
mod read;

pub use placement::{dem_area, georef_from_extent};

use std::path::Path;

use image::RgbaImage;

use crate::dem::Dem;
use crate::error::{Error, Result};
use crate::georef::{GridGeoref, WorldRect};

/// Where the ortho image lies in the world.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OrthoPlacement {
    /// From the file's GeoTIFF tags (ModelPixelScale + ModelTiepoint).
    FromFile,
    /// Pixel (r, c) lies on DEM sample (r, c) (same grid; sizes must match).
    SameGridAsDem,
    /// The image's outer pixel edges span this world rectangle.
    Extent(WorldRect),
}

/// An orthophoto: colour with coverage, placed in the world.
#[derive(Clone, Debug)]
pub struct Ortho {
    /// Colour; alpha 0 marks pixels without image data.
    pub image: RgbaImage,
    /// Pixel-centre georeference (same convention as the DEM's).
    pub georef: GridGeoref,
}

impl Ortho {
    /// Marks every pixel of exactly the colour `rgb` as unknown (alpha 0), for orthos that
    /// encode missing coverage as a colour (often black); returns the number of pixels marked.
    pub fn mask_colour(&mut self, rgb: [u8; 3]) -> usize {
        let mut n = 0;
        for p in self.image.pixels_mut() {
            if p.0[..3] == rgb && p.0[3] != 0 {
                p.0[3] = 0;
                n += 1;
            }
        }
        n
    }

    /// World rectangle covered by the image's outer pixel edges.
    pub fn extent(&self) -> WorldRect {
        let g = &self.georef;
        let (w, h) = (self.image.width() as f64, self.image.height() as f64);
        let (x0, y0) = g.world(-0.5, -0.5);
        let (x1, y1) = g.world(h - 0.5, w - 0.5);
        WorldRect {
            min_x: x0,
            min_y: y1,
            max_x: x1,
            max_y: y0,
        }
    }
}

/// Reads an ortho image and places it. Errors (naming the file) if it is unreadable, too
/// large for `max_memory` (checked from the header before decoding), lacks the placement
/// information `placement` needs, or does not overlap the DEM's sample areas.
pub fn load_ortho(
    path: &Path,
    placement: OrthoPlacement,
    dem: &Dem,
    max_memory: u64,
) -> Result<Ortho> {
    let d = read::read(path, max_memory)?;
    let georef = placement::place(
        path,
        placement,
        d.image.width(),
        d.image.height(),
        d.tags.as_ref(),
        dem,
    )?;
    if placement == OrthoPlacement::FromFile
        && let (Some(t), Some(dc)) = (
            d.tags.as_ref().and_then(|t| t.crs.as_deref()),
            dem.crs.as_deref(),
        )
        && t != dc
    {
        return Err(Error::bad_input(
            path,
            format!("ortho CRS {t} differs from the DEM's {dc}; reproject one of them"),
        ));
    }
    let ortho = Ortho {
        image: d.image,
        georef,
    };
    let area = dem_area(dem);
    let e = ortho.extent();
    if e.intersect(&area).is_none() {
        return Err(Error::bad_input(
            path,
            format!(
                "ortho covers x {:.3}..{:.3}, y {:.3}..{:.3}, which does not overlap the DEM (x {:.3}..{:.3}, y {:.3}..{:.3})",
                e.min_x, e.max_x, e.min_y, e.max_y, area.min_x, area.max_x, area.min_y, area.max_y
            ),
        ));
    }
    Ok(ortho)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tiffgen::{self, Geo, Raw};
    use image::{ImageBuffer, Rgb, Rgba};

    fn dem(w: usize, h: usize, g: GridGeoref) -> Dem {
        Dem::from_heights(w, h, vec![100.0; w * h], g).unwrap()
    }

    #[test]
    fn same_grid_extent_and_from_file_png() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("o.png");
        // pure black pixel at (0,0): ordinary colour, not no-data
        let img: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_fn(4, 3, |x, y| {
            if (x, y) == (0, 0) {
                Rgb([0, 0, 0])
            } else {
                Rgb([x as u8 * 50, y as u8 * 60, 7])
            }
        });
        img.save(&p).unwrap();
        let g = GridGeoref::new(445302.17, 7396769.45, 3.0);
        let dm = dem(4, 3, g);
        let o = load_ortho(&p, OrthoPlacement::SameGridAsDem, &dm, 1 << 30).unwrap();
        assert_eq!(o.georef, g);
        assert_eq!(*o.image.get_pixel(0, 0), Rgba([0, 0, 0, 255]));
        assert_eq!(*o.image.get_pixel(3, 2), Rgba([150, 120, 7, 255]));

        // size mismatch
        let e = load_ortho(&p, OrthoPlacement::SameGridAsDem, &dem(5, 3, g), 1 << 30)
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("o.png") && e.contains("4x3") && e.contains("5x3"),
            "{e}"
        );
        // no georeference in a PNG
        let e = load_ortho(&p, OrthoPlacement::FromFile, &dm, 1 << 30)
            .unwrap_err()
            .to_string();
        assert!(e.contains("o.png") && e.contains("--ortho-extent"), "{e}");

        // explicit extent of outer pixel edges
        let r = WorldRect {
            min_x: 445300.67,
            min_y: 7396761.95,
            max_x: 445312.67,
            max_y: 7396770.95,
        };
        let o = load_ortho(&p, OrthoPlacement::Extent(r), &dm, 1 << 30).unwrap();
        assert!((o.georef.spacing_x - 3.0).abs() < 1e-9 && (o.georef.spacing_y - 3.0).abs() < 1e-9);
        assert!(
            (o.georef.origin_x - 445302.17).abs() < 1e-9
                && (o.georef.origin_y - 7396769.45).abs() < 1e-9
        );
        let e = o.extent();
        assert!((e.min_x - r.min_x).abs() < 1e-9 && (e.max_y - r.max_y).abs() < 1e-9);

        // not overlapping the DEM
        let far = WorldRect {
            min_x: 0.0,
            min_y: 0.0,
            max_x: 10.0,
            max_y: 10.0,
        };
        let e = load_ortho(&p, OrthoPlacement::Extent(far), &dm, 1 << 30)
            .unwrap_err()
            .to_string();
        assert!(e.contains("o.png") && e.contains("does not overlap"), "{e}");
        // inverted extent
        let bad = WorldRect {
            min_x: 10.0,
            min_y: 0.0,
            max_x: 0.0,
            max_y: 10.0,
        };
        assert!(
            load_ortho(&p, OrthoPlacement::Extent(bad), &dm, 1 << 30)
                .unwrap_err()
                .to_string()
                .contains("o.png")
        );
        // memory limit checked from the header
        let e = load_ortho(&p, OrthoPlacement::SameGridAsDem, &dm, 40).unwrap_err();
        assert!(matches!(e, Error::TooLarge { .. }), "{e}");
    }

    #[test]
    fn rgba_alpha_and_jpeg() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("a.png");
        let img: ImageBuffer<Rgba<u8>, Vec<u8>> = ImageBuffer::from_fn(3, 3, |x, y| {
            Rgba([10, 20, 30, if (x, y) == (1, 2) { 0 } else { 255 }])
        });
        img.save(&p).unwrap();
        let dm = dem(3, 3, GridGeoref::new(0.0, 0.0, 1.0));
        let o = load_ortho(&p, OrthoPlacement::SameGridAsDem, &dm, 1 << 20).unwrap();
        assert_eq!(o.image.get_pixel(1, 2)[3], 0);
        assert_eq!(o.image.pixels().filter(|p| p[3] == 0).count(), 1);

        let j = d.path().join("c.jpg");
        let img: ImageBuffer<Rgb<u8>, Vec<u8>> = ImageBuffer::from_pixel(3, 3, Rgb([200, 100, 50]));
        img.save(&j).unwrap();
        let o = load_ortho(&j, OrthoPlacement::SameGridAsDem, &dm, 1 << 20).unwrap();
        let px = o.image.get_pixel(1, 1);
        assert!(
            px[3] == 255 && (px[0] as i32 - 200).abs() < 8 && (px[2] as i32 - 50).abs() < 8,
            "{px:?}"
        );
    }

    #[test]
    fn geotiff_rgb_and_rgba_from_file() {
        let d = tempfile::tempdir().unwrap();
        let (w, h) = (5u32, 4u32);
        let geo = Geo {
            scale: (0.5, 0.5),
            tie: (0.0, 0.0, 1000.0, 2000.0),
            pixel_is_point: false,
            epsg: Some(32633),
            nodata: Some("0".into()),
        };
        let mut rgb: Vec<u8> = (0..w * h).flat_map(|i| [i as u8 + 1, 2, 3]).collect();
        rgb[0..3].copy_from_slice(&[0, 0, 0]); // equals GDAL_NODATA 0 in every band -> no data
        let p = d.path().join("rgb.tif");
        tiffgen::write_strips::<tiff::encoder::colortype::RGB8>(
            &p,
            w,
            h,
            &rgb,
            Default::default(),
            tiff::tags::Predictor::None,
            Some(&geo),
        );
        let mut dm = dem(20, 20, GridGeoref::new(1000.0, 2000.0, 0.25));
        dm.crs = Some("EPSG:32633".into());
        let o = load_ortho(&p, OrthoPlacement::FromFile, &dm, 1 << 20).unwrap();
        assert_eq!(o.georef, GridGeoref::new(1000.25, 1999.75, 0.5));
        assert_eq!(o.image.get_pixel(0, 0)[3], 0);
        assert_eq!(*o.image.get_pixel(1, 0), Rgba([2, 2, 3, 255]));
        // CRS mismatch is refused
        dm.crs = Some("EPSG:25833".into());
        assert!(
            load_ortho(&p, OrthoPlacement::FromFile, &dm, 1 << 20)
                .unwrap_err()
                .to_string()
                .contains("EPSG:25833")
        );
        dm.crs = None;

        // tiled RGBA with unassociated alpha
        let rgba: Vec<u8> = (0..w * h)
            .flat_map(|i| [9, 8, 7, if i == 6 { 0 } else { 255 }])
            .collect();
        let raw = Raw {
            width: w,
            height: h,
            bits: 8,
            sample_format: 1,
            samples: 4,
            photometric: 2,
            tile: Some((16, 16)),
            extra_alpha: true,
        };
        let p = d.path().join("rgba.tif");
        tiffgen::write_raw(
            &p,
            &raw,
            &rgba,
            Some(&Geo {
                nodata: None,
                ..geo.clone()
            }),
            false,
        );
        let o = load_ortho(&p, OrthoPlacement::FromFile, &dm, 1 << 20).unwrap();
        assert_eq!(o.image.get_pixel(1, 1)[3], 0);
        assert_eq!(*o.image.get_pixel(0, 0), Rgba([9, 8, 7, 255]));
    }
}
