//! A photo as grey levels: f32 luminance (Rec. 709 weights of the sRGB values), box-filtered
//! to smaller sizes; what the patch matcher and the silhouette-edge stage read.

use image::RgbImage;

/// A grey image as f32 luminance (Rec. 709 weights of the sRGB values).
pub(crate) struct Grey {
    /// Width in pixels.
    pub(crate) w: usize,
    /// Height in pixels.
    pub(crate) h: usize,
    /// Row-major luminance (0..255).
    pub(crate) v: Vec<f32>,
}

impl Grey {
    pub(crate) fn of(img: &RgbImage) -> Grey {
        let v = img
            .pixels()
            .map(|p| 0.2126 * p.0[0] as f32 + 0.7152 * p.0[1] as f32 + 0.0722 * p.0[2] as f32)
            .collect();
        Grey {
            w: img.width() as usize,
            h: img.height() as usize,
            v,
        }
    }

    /// Box-filtered by `k` (the last partial blocks dropped).
    pub(crate) fn reduced(&self, k: usize) -> Grey {
        let (w, h) = (self.w / k, self.h / k);
        let mut v = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                let mut s = 0.0;
                for dy in 0..k {
                    let row = &self.v[(y * k + dy) * self.w + x * k..][..k];
                    s += row.iter().sum::<f32>();
                }
                v[y * w + x] = s / (k * k) as f32;
            }
        }
        Grey { w, h, v }
    }

}
