//! The per-channel affine colour map that levels a photo's colours to the existing textures
//! (fitted in [`crate::photo::leveling::colour_leveling`], applied before splatting in [`crate::photo::splatting::accumulate`]).

/// A per-channel affine colour map on sRGB values in [0, 1].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ColourTransform {
    /// Per-channel gain (1 = unchanged).
    pub gain: [f64; 3],
    /// Per-channel offset in [0, 1] units (0 = unchanged).
    pub offset: [f64; 3],
}

impl ColourTransform {
    /// The identity map.
    pub const IDENTITY: ColourTransform = ColourTransform {
        gain: [1.0; 3],
        offset: [0.0; 3],
    };

    /// `gain · rgb + offset`, clamped to [0, 1].
    #[inline]
    pub fn apply(&self, rgb: [f32; 3]) -> [f32; 3] {
        std::array::from_fn(|k| {
            (self.gain[k] as f32 * rgb[k] + self.offset[k] as f32).clamp(0.0, 1.0)
        })
    }
}
