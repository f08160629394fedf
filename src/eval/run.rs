//! A whole evaluation of a store: reference images, cliffmap's renders in three texture
//! modes (and optionally the TIN baseline) and their scores, per view.

use std::path::Path;

use image::RgbImage;

use super::reference::{Reference, ReferenceSources, reference_images};
use super::render::render_views_relief;
use super::score::{ViewReport, score_view};
use super::tin::{TinTracer, tin_references};
use crate::demo_scene::PhotoShot;
use crate::error::Result;
use crate::render::UvMode;
use crate::store::Store;

/// The texture modes rendered, with their method names: the ortho alone, the reparameterized
/// textures (as stored, no photos) and each cell's best texture (`cliffmap render`'s default).
pub const MODES: [(&str, UvMode); 3] = [
    ("ortho", UvMode::Ortho),
    ("reparam", UvMode::Mixed),
    ("photo", UvMode::Photo),
];

/// Name of the baseline on the store's TIN.
pub const TIN_BASELINE: &str = "tin_baseline";
/// Name of the oracle on the store's TIN.
pub const TIN_ORACLE: &str = "tin_oracle";

/// How an evaluation runs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EvalOptions {
    /// Rays per pixel side of the reference images (1..=8). Default 2.
    pub supersample: u32,
    /// Samples per pixel side of cliffmap's renders (1..=8), as `cliffmap render`'s default.
    /// Default 2.
    pub render_supersample: u32,
    /// Screen-space error of the renders, pixels. Default 0.5.
    pub sse_px: f64,
    /// Standard deviation of the low-pass, pixels. Default 2.
    pub sigma_px: f64,
    /// Also score the references on the store's finest TIN: the ortho draped on it (method
    /// `tin_baseline`) and ideal projective texturing through it (method `tin_oracle`).
    pub tin_baseline: bool,
    /// Relief mapping in cliffmap's renders ([`crate::render::SceneOptions::relief`]).
    /// Default on, as `cliffmap render`.
    pub relief: bool,
}

impl Default for EvalOptions {
    fn default() -> Self {
        EvalOptions {
            supersample: 2,
            render_supersample: 2,
            sse_px: 0.5,
            sigma_px: 2.0,
            tin_baseline: true,
            relief: true,
        }
    }
}

/// One view's images: the reference and cliffmap's renders (name, image) in [`MODES`] order,
/// then the TIN baseline if asked for.
#[derive(Clone, Debug)]
pub struct ViewImages {
    /// View name.
    pub view: String,
    /// Truth, oracle, baseline and pixel classes.
    pub reference: Reference,
    /// The scored renders.
    pub renders: Vec<(String, RgbImage)>,
}

/// Evaluates the store in `dir` from `views` (all of one size) against `src` (see the
/// [module docs](super)). Needs a GPU driver (Mesa's software drivers suffice).
pub fn evaluate_views(
    dir: &Path,
    src: &ReferenceSources,
    views: &[PhotoShot],
    opts: &EvalOptions,
) -> Result<(Vec<ViewReport>, Vec<ViewImages>)> {
    let cams: Vec<_> = views.iter().map(|v| v.camera).collect();
    let renders = render_views_relief(
        dir,
        &cams,
        &MODES.map(|m| m.1),
        opts.sse_px,
        opts.render_supersample,
        opts.relief,
    )?;
    let tin = if opts.tin_baseline {
        let store = Store::open(dir)?;
        let finest = store.manifest.quadtree.levels.saturating_sub(1);
        Some(TinTracer::new(&store, finest, src.tracer.origin())?)
    } else {
        None
    };
    let mut reports = Vec::with_capacity(views.len());
    let mut images = Vec::with_capacity(views.len());
    for (vi, v) in views.iter().enumerate() {
        let reference = reference_images(src, &v.camera, opts.supersample)?;
        let mut methods: Vec<(String, RgbImage)> = MODES
            .iter()
            .enumerate()
            .map(|(mi, (name, _))| (name.to_string(), renders[mi][vi].clone()))
            .collect();
        if let Some(t) = &tin {
            let (b, o) = tin_references(t, src.ortho, src.photos, &v.camera, opts.supersample)?;
            methods.push((TIN_BASELINE.into(), b));
            methods.push((TIN_ORACLE.into(), o));
        }
        reports.push(score_view(&v.name, &reference, &methods, opts.sigma_px)?);
        images.push(ViewImages {
            view: v.name.clone(),
            reference,
            renders: methods,
        });
    }
    Ok((reports, images))
}

/// Writes a view's images into `dir`: `VIEW_{truth,oracle,baseline}.png`, one PNG per
/// render (`VIEW_photo.png`, ...), `VIEW_classes.png` (red steep, green flat, blue covered
/// by a photo, black sky) and `VIEW_side_by_side.png` (ortho | reparam | photo | truth,
/// captioned). Atomic writes; errors name the file.
pub fn write_view_images(dir: &Path, v: &ViewImages) -> Result<()> {
    use crate::fsutil::write_png_atomic;
    let r = &v.reference;
    for (name, img) in [
        ("truth", &r.truth),
        ("oracle", &r.oracle),
        ("baseline", &r.baseline),
    ] {
        write_png_atomic(&dir.join(format!("{}_{name}.png", v.view)), img)?;
    }
    for (name, img) in &v.renders {
        write_png_atomic(&dir.join(format!("{}_{name}.png", v.view)), img)?;
    }
    let (w, h) = r.truth.dimensions();
    let classes = RgbImage::from_fn(w, h, |x, y| {
        let c = r.classes[(y * w + x) as usize];
        let on = |bit: u8| if c & bit != 0 { 255 } else { 0 };
        image::Rgb([on(super::STEEP), on(super::FLAT), on(super::COVERED)])
    });
    write_png_atomic(&dir.join(format!("{}_classes.png", v.view)), &classes)?;
    let find = |n: &str| v.renders.iter().find(|(m, _)| m == n).map(|(_, i)| i);
    if let (Some(o), Some(re), Some(p)) = (find("ortho"), find("reparam"), find("photo")) {
        let tiles = [
            (o, "ortho"),
            (re, "reparameterized"),
            (p, "photo-enhanced (default)"),
            (&r.truth, "ground truth"),
        ];
        if let Some(s) = super::side_by_side(&tiles) {
            write_png_atomic(&dir.join(format!("{}_side_by_side.png", v.view)), &s)?;
        }
    }
    Ok(())
}
