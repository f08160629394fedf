//! Render-space evaluation of texture fidelity on a scene with exact ground truth
//! (docs/evaluation.md).
//!
//! A view is ray cast exactly against the full-resolution DEM ([`reference_images`]): the
//! **truth** (the demo scene's solid texture at every hit), the **oracle** (ideal projective
//! texturing: per ray, the photo with the finest surface footprint that sees the hit point,
//! sampled at its projection and filtered over the ray's footprint in it, else the ortho) and the **baseline** (the ortho
//! draped at the hit point), with per pixel its class (terrain, steep > 60°, flat < 30°,
//! covered by a photo). cliffmap's own renders of the store ([`render_views`], headless and
//! unlit, as `cliffmap render --unlit`) are then scored against the truth ([`score_view`]):
//! PSNR per class at full resolution and after a Gaussian low-pass (σ = 2 px by default),
//! and the gains over the baseline as a share of the oracle's gain.
//!
//! [`tin_references`] casts against the store's own TIN instead of the DEM (ortho draped on
//! it, and ideal projective texturing through it): the gaps to the DEM references are what
//! the TIN's geometric error costs.
//!
//! Data types: [`ReferenceSources`] (scene, tracer, ortho, photos) → [`Reference`] (three
//! images + classes) → [`ViewReport`] (a [`MethodScore`] of [`ClassScore`]s per method).

mod metrics;
mod reference;
#[cfg(feature = "render")]
mod render;
#[cfg(feature = "render")]
mod run;
mod score;
mod side_by_side;
mod tin;

pub use metrics::{ClassScore, Plane, low_pass, plane, psnr_masked};
pub use reference::{
    COVERED, FLAT, PhotoMips, Reference, ReferenceSources, STEEP, TERRAIN, VISIBILITY_TOLERANCE_M,
    VISIBILITY_TOLERANCE_REL, finest_photo, finest_photo_with, oracle_colour, ortho_colour,
    reference_images,
};
#[cfg(feature = "render")]
pub use render::{render_views, render_views_relief};
#[cfg(feature = "render")]
pub use run::{
    EvalOptions, MODES, TIN_BASELINE, TIN_ORACLE, ViewImages, evaluate_views, write_view_images,
};
pub use score::{BASELINE, Class, MethodScore, ORACLE, ViewReport, gains_table, score_view};
pub use side_by_side::side_by_side;
pub use tin::{TinTracer, tin_references};
