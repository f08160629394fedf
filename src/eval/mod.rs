//! Render-space evaluation of texture fidelity on a scene with exact ground truth
//! (docs/evaluation.md).
//!
//! A view is ray cast exactly against the full-resolution DEM ([`reference_images`]): the
//! **truth** (the demo scene's solid texture at every hit), the **oracle** (ideal projective
//! texturing: per ray, the photo with the finest surface footprint that sees the hit point,
//! sampled bilinearly at its projection, else the ortho) and the **baseline** (the ortho
//! draped at the hit point), with per pixel its class (terrain, steep > 60°, flat < 30°,
//! covered by a photo). cliffmap's own renders of the store ([`render_views`], headless and
//! unlit, as `cliffmap render --unlit`) are then scored against the truth ([`score_view`]):
//! PSNR per class at full resolution and after a Gaussian low-pass (σ = 2 px by default),
//! and the gains over the baseline as a share of the oracle's gain.
//!
//! [`tin_baseline`] drapes the ortho on the store's own TIN instead of the DEM: the gap
//! between the two baselines is what the TIN's geometric error costs.
//!
//! Data types: [`ReferenceSources`] (scene, tracer, ortho, photos) → [`Reference`] (three
//! images + classes) → [`ViewReport`] (a [`MethodScore`] of [`ClassScore`]s per method).

mod metrics;
mod reference;
mod render;
mod score;
mod tiles;
mod tin;

pub use metrics::{ClassScore, Plane, low_pass, plane, psnr_masked};
pub use reference::{COVERED, FLAT, Reference, ReferenceSources, STEEP, TERRAIN, finest_photo, ortho_colour, reference_images};
pub use render::render_views;
pub use score::{BASELINE, Class, MethodScore, ORACLE, ViewReport, gains_table, score_view};
pub use tiles::side_by_side;
pub use tin::{TinTracer, tin_baseline};
