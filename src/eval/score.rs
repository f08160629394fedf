//! Scores of rendered images against a view's [`Reference`]: PSNR per pixel class, full
//! resolution and low-pass, and gains over the baseline.

use image::RgbImage;
use serde::Serialize;

use super::metrics::{ClassScore, Plane, low_pass, plane, psnr_masked};
use super::reference::{COVERED, FLAT, Reference, STEEP, TERRAIN};

/// Name of the baseline method in a [`ViewReport`]: the ortho draped at the exact hit points.
pub const BASELINE: &str = "baseline";
/// Name of the oracle method in a [`ViewReport`]: ideal projective texturing from the photos.
pub const ORACLE: &str = "oracle";

/// One method's scores in one view.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MethodScore {
    /// Method name ([`BASELINE`], [`ORACLE`] or the caller's, e.g. `"photo"`).
    pub method: String,
    /// Steep (> 60°) pixels that a photo covers: what photo projection is for.
    pub steep_covered: ClassScore,
    /// Flat (< 30°) pixels.
    pub flat: ClassScore,
    /// Flat pixels that a photo covers.
    pub flat_covered: ClassScore,
    /// All terrain pixels.
    pub terrain: ClassScore,
}

/// Every method's scores in one view.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ViewReport {
    /// View name.
    pub view: String,
    /// Standard deviation of the low-pass, pixels.
    pub sigma_px: f64,
    /// The baseline, the oracle, then the caller's methods in order.
    pub methods: Vec<MethodScore>,
}

/// Which class and resolution a gain is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// Steep covered pixels.
    SteepCovered,
    /// Flat pixels.
    Flat,
    /// Flat covered pixels.
    FlatCovered,
    /// All terrain pixels.
    Terrain,
}

impl MethodScore {
    /// The score of `class`.
    pub fn class(&self, class: Class) -> &ClassScore {
        match class {
            Class::SteepCovered => &self.steep_covered,
            Class::Flat => &self.flat,
            Class::FlatCovered => &self.flat_covered,
            Class::Terrain => &self.terrain,
        }
    }
}

impl ViewReport {
    /// The scores of `method`, if it was scored.
    pub fn method(&self, method: &str) -> Option<&MethodScore> {
        self.methods.iter().find(|m| m.method == method)
    }

    /// PSNR gain of `method` over the baseline on `class` (dB): `[full resolution, low-pass]`.
    pub fn gain(&self, method: &str, class: Class) -> Option<[f64; 2]> {
        let m = self.method(method)?.class(class);
        let b = self.method(BASELINE)?.class(class);
        Some([m.psnr - b.psnr, m.psnr_low - b.psnr_low])
    }

    /// `method`'s gain on steep covered pixels as a fraction of the oracle's:
    /// `[full resolution, low-pass]`.
    pub fn oracle_fraction(&self, method: &str) -> Option<[f64; 2]> {
        self.fraction_of(method, ORACLE)
    }

    /// `method`'s gain on steep covered pixels as a fraction of `reference`'s (e.g. the
    /// oracle on the store's TIN): `[full resolution, low-pass]`.
    pub fn fraction_of(&self, method: &str, reference: &str) -> Option<[f64; 2]> {
        let g = self.gain(method, Class::SteepCovered)?;
        let o = self.gain(reference, Class::SteepCovered)?;
        Some([g[0] / o[0], g[1] / o[1]])
    }
}

/// Scores the baseline, the oracle and `methods` (name, image of the reference's size) of
/// one view. Pixels where the truth shows sky are set to the truth's colour in every image
/// first, so the low-pass does not mix sky into terrain differently per method; a method
/// that draws sky over terrain (or terrain over sky) keeps that error. Errors if an image
/// has another size.
pub fn score_view(
    view: &str,
    r: &Reference,
    methods: &[(String, RgbImage)],
    sigma_px: f64,
) -> crate::Result<ViewReport> {
    let (w, h) = r.truth.dimensions();
    let (wu, hu) = (w as usize, h as usize);
    let truth = plane(&r.truth);
    let truth_low = low_pass(&truth, wu, hu, sigma_px);
    let score = |name: &str, img: &RgbImage| -> crate::Result<MethodScore> {
        if img.dimensions() != (w, h) {
            return Err(crate::Error::BadOption(format!(
                "image of {name} is {:?}, the view is {w}x{h}",
                img.dimensions()
            )));
        }
        let mut p: Plane = plane(img);
        for (i, px) in p.iter_mut().enumerate() {
            if r.classes[i] & TERRAIN == 0 {
                *px = truth[i];
            }
        }
        let low = low_pass(&p, wu, hu, sigma_px);
        let class = |bits: u8| {
            let m = |i: usize| r.classes[i] & bits == bits;
            let (psnr, pixels) = psnr_masked(&p, &truth, m);
            let (psnr_low, _) = psnr_masked(&low, &truth_low, m);
            ClassScore {
                pixels,
                psnr,
                psnr_low,
            }
        };
        Ok(MethodScore {
            method: name.to_string(),
            steep_covered: class(TERRAIN | STEEP | COVERED),
            flat: class(TERRAIN | FLAT),
            flat_covered: class(TERRAIN | FLAT | COVERED),
            terrain: class(TERRAIN),
        })
    };
    let mut out = vec![score(BASELINE, &r.baseline)?, score(ORACLE, &r.oracle)?];
    for (name, img) in methods {
        out.push(score(name, img)?);
    }
    Ok(ViewReport {
        view: view.to_string(),
        sigma_px,
        methods: out,
    })
}

/// A Markdown table of the gains over the baseline per view and method: steep covered
/// pixels (full / low-pass), the fraction of the oracle's gain, and flat pixels.
pub fn gains_table(reports: &[ViewReport]) -> String {
    let mut s = String::from(
        "| view | method | steep covered: PSNR dB (full / low-pass) | gain over baseline | share of oracle gain | share of TIN oracle gain | flat: gain over baseline (full / low-pass) |\n|---|---|---|---|---|---|---|\n",
    );
    for r in reports {
        for m in &r.methods {
            let sc = &m.steep_covered;
            let g = r
                .gain(&m.method, Class::SteepCovered)
                .unwrap_or([f64::NAN; 2]);
            let f = r.oracle_fraction(&m.method).unwrap_or([f64::NAN; 2]);
            let fl = r.gain(&m.method, Class::Flat).unwrap_or([f64::NAN; 2]);
            let reference =
                m.method == BASELINE || m.method == ORACLE || m.method.starts_with("tin_");
            let pct = |f: [f64; 2]| {
                if reference || f[0].is_nan() {
                    String::new()
                } else {
                    format!("{:.0} % / {:.0} %", 100.0 * f[0], 100.0 * f[1])
                }
            };
            let share = pct(f);
            let tin_share = pct(r
                .fraction_of(&m.method, "tin_oracle")
                .unwrap_or([f64::NAN; 2]));
            let view = if m.method == BASELINE {
                format!(
                    "{} ({} steep covered, {} flat px)",
                    r.view, sc.pixels, m.flat.pixels
                )
            } else {
                r.view.clone()
            };
            s += &format!(
                "| {} | {} | {:.2} / {:.2} | {:+.2} / {:+.2} | {} | {} | {:+.2} / {:+.2} |\n",
                view, m.method, sc.psnr, sc.psnr_low, g[0], g[1], share, tin_share, fl[0], fl[1]
            );
        }
    }
    s
}
