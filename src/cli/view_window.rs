//! The window side of `cliffmap view`: surface configuration (recreated on resize), presenting
//! an offscreen frame by a copy, and mouse capture for mouse look.

use anyhow::{anyhow, bail};
use winit::window::{CursorGrabMode, Window};

/// Tries the grab modes in order of preference — `Locked` (cursor fixed, raw motion), then
/// `Confined` (cursor kept inside the window; X11 has no lock) — with `grab`; returns the
/// first that works, or `None` if the platform supports neither.
pub fn try_grab<E>(
    mut grab: impl FnMut(CursorGrabMode) -> Result<(), E>,
) -> Option<CursorGrabMode> {
    [CursorGrabMode::Locked, CursorGrabMode::Confined]
        .into_iter()
        .find(|&m| grab(m).is_ok())
}

/// Captures the mouse for mouse look (hidden cursor, grabbed as [`try_grab`] can); `None` if
/// the window cannot grab the cursor (it stays visible and free).
pub fn capture(window: &Window) -> Option<CursorGrabMode> {
    let mode = try_grab(|m| window.set_cursor_grab(m))?;
    window.set_cursor_visible(false);
    Some(mode)
}

/// Releases a capture made by [`capture`].
pub fn release(window: &Window) {
    let _ = window.set_cursor_grab(CursorGrabMode::None);
    window.set_cursor_visible(true);
}

/// A window surface that accepts copies of RGBA8 frames.
pub struct Presenter {
    /// The surface of the window.
    pub surface: wgpu::Surface<'static>,
    /// Its configuration (size = the window's inner size).
    pub config: wgpu::SurfaceConfiguration,
    /// True if the surface is BGRA (frames are swizzled before the copy).
    pub bgra: bool,
}

impl Presenter {
    /// Picks an 8-bit RGBA/BGRA format that accepts copies and configures `surface` at
    /// `width × height` for `device`.
    pub fn new(
        surface: wgpu::Surface<'static>,
        adapter: &wgpu::Adapter,
        device: &wgpu::Device,
        width: u32,
        height: u32,
    ) -> anyhow::Result<Presenter> {
        let caps = surface.get_capabilities(adapter);
        if !caps.usages.contains(wgpu::TextureUsages::COPY_DST) {
            bail!("the window surface does not accept copies (COPY_DST) on this adapter");
        }
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                matches!(
                    f,
                    wgpu::TextureFormat::Rgba8UnormSrgb
                        | wgpu::TextureFormat::Bgra8UnormSrgb
                        | wgpu::TextureFormat::Rgba8Unorm
                        | wgpu::TextureFormat::Bgra8Unorm
                )
            })
            .ok_or_else(|| anyhow!("the window surface offers no 8-bit RGBA/BGRA format"))?;
        let bgra = matches!(
            format,
            wgpu::TextureFormat::Bgra8UnormSrgb | wgpu::TextureFormat::Bgra8Unorm
        );
        let mut config = surface
            .get_default_config(adapter, width, height)
            .ok_or_else(|| anyhow!("the window surface is not supported by the adapter"))?;
        config.format = format;
        config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        config.view_formats.clear();
        surface.configure(device, &config);
        Ok(Presenter {
            surface,
            config,
            bgra,
        })
    }

    /// Reconfigures the surface at `width × height` (both > 0).
    pub fn resize(&mut self, device: &wgpu::Device, width: u32, height: u32) {
        self.config.width = width;
        self.config.height = height;
        self.surface.configure(device, &self.config);
    }

    /// Copies `img` (sRGB RGBA8, the surface's size or smaller) into the next surface texture
    /// and presents it. Returns false if the surface was outdated or lost (it is reconfigured;
    /// the frame is dropped) or had no texture available.
    pub fn present(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mut img: image::RgbaImage,
    ) -> bool {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(device, &self.config);
                return false;
            }
            _ => return false,
        };
        if self.bgra {
            for px in img.pixels_mut() {
                px.0.swap(0, 2);
            }
        }
        let (w, h) = img.dimensions();
        let t = &frame.texture;
        let (cw, ch) = (w.min(t.width()), h.min(t.height()));
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: t,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            img.as_raw(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * w),
                rows_per_image: Some(h),
            },
            wgpu::Extent3d {
                width: cw,
                height: ch,
                depth_or_array_layers: 1,
            },
        );
        queue.submit([]);
        queue.present(frame);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grab_prefers_locked_and_falls_back_to_confined() {
        assert_eq!(try_grab(|_| Ok::<(), ()>(())), Some(CursorGrabMode::Locked));
        let x11 = |m: CursorGrabMode| {
            if m == CursorGrabMode::Locked {
                Err(())
            } else {
                Ok(())
            }
        };
        assert_eq!(try_grab(x11), Some(CursorGrabMode::Confined));
        assert_eq!(try_grab(|_| Err::<(), ()>(())), None);
    }
}
