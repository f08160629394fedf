//! `cliffmap view`: an interactive window (winit) over a store with a fly camera.
//!
//! Each frame is rendered offscreen by [`TerrainScene`] on a device opened for the window's
//! surface, read back and written into the surface texture (a copy, so the renderer stays
//! headless). Keys: WASD move, Q/E down/up, Shift faster, mouse drag look, L levels + boxes,
//! H stretch heat map, M texture mode, +/− threshold, Esc quit.

use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use cliffmap::render::{
    FlightPath, FlyCamera, FlyInput, FrameReport, GpuContext, Overlay, SceneOptions,
    TerrainScene, UvMode, adjust_sse,
};
use cliffmap::store::Store;
use glam::DVec3;
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Flags of `cliffmap view`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Window size, e.g. 1280x720 (the render target keeps this size).
    #[arg(long, value_parser = super::render::parse_size, default_value = "1280x720")]
    size: (u32, u32),
    /// Initial screen-space error threshold in pixels.
    #[arg(long, default_value_t = 0.5)]
    sse: f64,
}

/// Mouse-look sensitivity, radians per pixel of drag.
const LOOK_RAD_PER_PX: f64 = 0.004;

/// Whether a display server is reachable by environment (X11 `DISPLAY` or `WAYLAND_DISPLAY`
/// set and non-empty); other platforms are assumed to have one.
fn display_available(var: impl Fn(&str) -> Option<String>) -> bool {
    if !cfg!(all(unix, not(target_os = "macos"))) {
        return true;
    }
    ["DISPLAY", "WAYLAND_DISPLAY"]
        .iter()
        .any(|k| var(k).is_some_and(|v| !v.trim().is_empty()))
}

/// The texture modes the store can show, in M-key order.
fn texture_modes(store: &Store) -> Vec<UvMode> {
    let cells = &store.manifest.cells;
    let mut modes = vec![UvMode::Ortho];
    if cells.iter().any(|c| c.reparam.is_some()) {
        modes.push(UvMode::Mixed);
    }
    if cells.iter().any(|c| c.photo.is_some()) {
        modes.push(UvMode::Photo);
    }
    modes
}

fn mode_name(m: UvMode) -> &'static str {
    match m {
        UvMode::Ortho => "ortho",
        UvMode::Mixed | UvMode::Reparam => "reparam",
        UvMode::Photo => "photo",
    }
}

/// Runs the command.
pub fn run(a: Args) -> anyhow::Result<()> {
    // Validate the store before touching the display, so a bad path is reported as such.
    let store = Store::open(&a.store)?;
    let modes = texture_modes(&store);
    let path = FlightPath::default_for(&store.manifest)
        .with_context(|| format!("no starting view for {}", a.store.display()))?;
    if !(a.sse.is_finite() && a.sse > 0.0) {
        bail!("--sse must be a positive number of pixels, got {}", a.sse);
    }
    if !display_available(|k| std::env::var(k).ok()) {
        bail!(
            "no display available (DISPLAY and WAYLAND_DISPLAY are unset): `cliffmap view` needs a \
             window; use `cliffmap render` or `cliffmap fly` for headless frames"
        );
    }
    let event_loop =
        EventLoop::new().map_err(|e| anyhow!("cannot connect to the display: {e}"))?;
    let mut app = App {
        args: a,
        modes,
        path,
        state: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window event loop failed: {e}"))?;
    match app.error {
        Some(e) => Err(e),
        None => Ok(()),
    }
}

struct App {
    args: Args,
    modes: Vec<UvMode>,
    path: FlightPath,
    state: Option<ViewState>,
    error: Option<anyhow::Error>,
}

struct ViewState {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    bgra: bool,
    scene: TerrainScene,
    cam: FlyCamera,
    fov_y: f64,
    size: (u32, u32),
    keys: HashSet<KeyCode>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    mode: usize,
    overlay: Overlay,
    last: Instant,
    report: FrameReport,
}

impl App {
    fn fail(&mut self, el: &ActiveEventLoop, e: anyhow::Error) {
        self.error = Some(e);
        el.exit();
    }

    fn open(&self, el: &ActiveEventLoop) -> anyhow::Result<ViewState> {
        let (w, h) = self.args.size;
        let attrs = Window::default_attributes()
            .with_title("cliffmap view")
            .with_inner_size(winit::dpi::PhysicalSize::new(w, h))
            .with_resizable(false);
        let window = Arc::new(el.create_window(attrs).context("cannot create a window")?);
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
            Box::new(Arc::clone(&window)),
        ));
        let surface = instance
            .create_surface(Arc::clone(&window))
            .context("cannot create a drawing surface for the window")?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| anyhow!("no graphics adapter can draw to the window ({e})"))?;
        let caps = surface.get_capabilities(&adapter);
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
        let ctx = GpuContext::from_adapter(adapter)?;
        eprintln!("adapter: {}", ctx.describe());
        let mut config = surface
            .get_default_config(&ctx.adapter, w, h)
            .ok_or_else(|| anyhow!("the window surface is not supported by the adapter"))?;
        config.format = format;
        config.usage = wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_DST;
        config.view_formats.clear();
        surface.configure(&ctx.device, &config);
        let mode = self.modes.len() - 1;
        let mode = if self.modes[mode] == UvMode::Photo && mode > 0 { mode - 1 } else { mode };
        let opts = SceneOptions {
            sse_px: self.args.sse,
            uv_mode: self.modes[mode],
            ..Default::default()
        };
        let scene = TerrainScene::open_with_context(&self.args.store, ctx, w, h, opts)?;
        let k = &self.path.keys[0];
        let (p, t) = (DVec3::from(k.position), DVec3::from(k.look_at));
        let r = &scene.store().manifest.cells;
        let extent = r
            .iter()
            .filter(|c| c.level == 0)
            .map(|c| (DVec3::from(c.bbox_max) - DVec3::from(c.bbox_min)).truncate().length())
            .fold(0.0, f64::max);
        // Cross the terrain in about 30 s at base speed.
        let cam = FlyCamera::look_at(p, t, (extent / 30.0).max(1.0));
        Ok(ViewState {
            window,
            surface,
            config,
            bgra,
            scene,
            cam,
            fov_y: self.path.fov_y_deg.to_radians(),
            size: (w, h),
            keys: HashSet::new(),
            dragging: false,
            cursor: None,
            mode,
            overlay: Overlay::None,
            last: Instant::now(),
            report: FrameReport::default(),
        })
    }
}

impl ViewState {
    fn input(&self) -> FlyInput {
        let k = |c: KeyCode| self.keys.contains(&c) as i32 as f64;
        FlyInput {
            forward: k(KeyCode::KeyW) - k(KeyCode::KeyS),
            right: k(KeyCode::KeyD) - k(KeyCode::KeyA),
            up: k(KeyCode::KeyE) - k(KeyCode::KeyQ),
            fast: self.keys.contains(&KeyCode::ShiftLeft) || self.keys.contains(&KeyCode::ShiftRight),
        }
    }

    /// Handles a key press; `Ok(false)` asks to quit.
    fn key(&mut self, code: KeyCode, modes: &[UvMode]) -> anyhow::Result<bool> {
        match code {
            KeyCode::Escape => return Ok(false),
            KeyCode::KeyL | KeyCode::KeyH => {
                let o = if code == KeyCode::KeyL { Overlay::Levels } else { Overlay::Stretch };
                self.overlay = if self.overlay == o { Overlay::None } else { o };
                self.scene.set_mode(modes[self.mode], self.overlay);
            }
            KeyCode::KeyM => {
                self.mode = (self.mode + 1) % modes.len();
                self.scene.set_mode(modes[self.mode], self.overlay);
            }
            KeyCode::Equal | KeyCode::NumpadAdd => {
                self.scene.set_sse(adjust_sse(self.scene.options().sse_px, 1))?;
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                self.scene.set_sse(adjust_sse(self.scene.options().sse_px, -1))?;
            }
            _ => {}
        }
        Ok(true)
    }

    fn redraw(&mut self, modes: &[UvMode]) -> anyhow::Result<()> {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f64().min(0.25);
        self.last = now;
        self.cam.step(self.input(), dt);
        let (w, h) = self.size;
        let model = self.cam.model(w, h, self.fov_y);
        self.report = self.scene.frame(&model, false)?;
        let mut img = self.scene.read_rgba()?;
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t) | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                self.surface.configure(&self.scene.gpu().device, &self.config);
                return Ok(());
            }
            _ => return Ok(()),
        };
        if self.bgra {
            for px in img.pixels_mut() {
                px.0.swap(0, 2);
            }
        }
        let t = &frame.texture;
        let (cw, ch) = (w.min(t.width()), h.min(t.height()));
        self.scene.gpu().queue.write_texture(
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
        self.scene.gpu().queue.submit([]);
        self.scene.gpu().queue.present(frame);
        let r = &self.report;
        let ov = match self.overlay {
            Overlay::None => "",
            Overlay::Levels => " + levels",
            Overlay::Stretch => " + stretch",
        };
        self.window.set_title(&format!(
            "cliffmap view — {:.1} ms ({:.1} fps), {} cells, {} triangles, {}{}, SSE {:.3} px",
            r.frame_ms,
            if dt > 0.0 { 1.0 / dt } else { 0.0 },
            r.drawn,
            r.triangles,
            mode_name(modes[self.mode]),
            ov,
            self.scene.options().sse_px,
        ));
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, el: &ActiveEventLoop) {
        if self.state.is_some() {
            return;
        }
        match self.open(el) {
            Ok(s) => {
                s.window.request_redraw();
                self.state = Some(s);
            }
            Err(e) => self.fail(el, e),
        }
    }

    fn window_event(&mut self, el: &ActiveEventLoop, _id: WindowId, event: WindowEvent) {
        let Some(s) = self.state.as_mut() else {
            return;
        };
        let result = match event {
            WindowEvent::CloseRequested => {
                el.exit();
                Ok(())
            }
            WindowEvent::KeyboardInput { event, .. } => {
                if let PhysicalKey::Code(code) = event.physical_key {
                    match event.state {
                        ElementState::Pressed => {
                            s.keys.insert(code);
                            if event.repeat {
                                Ok(())
                            } else {
                                s.key(code, &self.modes).map(|go| {
                                    if !go {
                                        el.exit();
                                    }
                                })
                            }
                        }
                        ElementState::Released => {
                            s.keys.remove(&code);
                            Ok(())
                        }
                    }
                } else {
                    Ok(())
                }
            }
            WindowEvent::MouseInput { state, button: MouseButton::Left, .. } => {
                s.dragging = state == ElementState::Pressed;
                Ok(())
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y))) = (s.dragging, s.cursor) {
                    s.cam.look(position.x - x, position.y - y, LOOK_RAD_PER_PX);
                }
                s.cursor = Some((position.x, position.y));
                Ok(())
            }
            WindowEvent::Focused(false) => {
                s.keys.clear();
                s.dragging = false;
                Ok(())
            }
            WindowEvent::RedrawRequested => {
                let r = s.redraw(&self.modes);
                s.window.request_redraw();
                r
            }
            _ => Ok(()),
        };
        if let Err(e) = result {
            self.fail(el, e);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn display_detection_reads_both_variables() {
        let env = |pairs: &'static [(&'static str, &'static str)]| {
            move |k: &str| pairs.iter().find(|(n, _)| *n == k).map(|(_, v)| v.to_string())
        };
        if cfg!(all(unix, not(target_os = "macos"))) {
            assert!(!display_available(env(&[])));
            assert!(!display_available(env(&[("DISPLAY", " ")])));
            assert!(display_available(env(&[("DISPLAY", ":0")])));
            assert!(display_available(env(&[("WAYLAND_DISPLAY", "wayland-0")])));
        }
    }
}
