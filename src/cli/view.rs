//! `cliffmap view`: an interactive window (winit) over a store with a fly camera.
//!
//! Each frame is rendered offscreen by [`StoreRenderer`] on a device opened for the window's
//! surface, read back and written into the surface texture (a copy, so the renderer stays
//! headless); the surface and the render target follow window resizes. Keys: WASD move, Q/E
//! down/up, Shift faster, mouse drag look, Tab or right button capture the mouse for mouse
//! look, G geomorphing, L levels + boxes, H stretch heat map, P photo share, M texture mode,
//! +/− threshold, Esc release the mouse / quit.

use std::collections::HashSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use anyhow::{Context, anyhow, bail};
use cliffmap::render::{
    FlightPath, FlyCamera, FlyInput, FrameReport, GeomorphOptions, GpuContext, Overlay,
    SceneOptions, StoreRenderer, UvMode, adjust_sse,
};
use cliffmap::store::Store;
use glam::DVec3;
use winit::application::ApplicationHandler;
use winit::event::{DeviceEvent, DeviceId, ElementState, MouseButton, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{CursorGrabMode, Window, WindowId};

use super::view_window::{Presenter, capture, release};

/// Flags of `cliffmap view`.
#[derive(clap::Args, Debug)]
pub struct Args {
    /// The store directory.
    store: PathBuf,
    /// Initial window size, e.g. 1280x720 (the window can be resized).
    #[arg(long, value_parser = super::render::parse_size, default_value = "1280x720")]
    size: (u32, u32),
    /// Initial screen-space error threshold in pixels.
    #[arg(long, default_value_t = 0.5)]
    sse: f64,
    /// Start with geomorphing on (G toggles it).
    #[arg(long)]
    geomorph: bool,
    /// Exit after presenting this many frames (scripted runs).
    #[arg(long)]
    frames: Option<u64>,
    /// Scripted smoke test: during the first frames, resize the window, capture and release
    /// the mouse and toggle geomorphing, reporting each step on stderr; exits after --frames
    /// (default 8).
    #[arg(long, hide = true)]
    smoke_test: bool,
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
    if a.frames == Some(0) {
        bail!("--frames must be at least 1");
    }
    if !display_available(|k| std::env::var(k).ok()) {
        bail!(
            "no display available (DISPLAY and WAYLAND_DISPLAY are unset): `cliffmap view` needs a \
             window; use `cliffmap render` or `cliffmap fly` for headless frames"
        );
    }
    let event_loop = EventLoop::new().map_err(|e| anyhow!("cannot connect to the display: {e}"))?;
    let exit_after = a.frames.or(a.smoke_test.then_some(8));
    let mut app = App {
        args: a,
        modes,
        path,
        exit_after,
        state: None,
        error: None,
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| anyhow!("window event loop failed: {e}"))?;
    if let Some(e) = app.error {
        return Err(e);
    }
    if let (Some(n), Some(s)) = (app.exit_after, &app.state) {
        if s.presented < n {
            bail!("only {} of {n} frames could be presented", s.presented);
        }
        let (w, h) = s.scene.size();
        eprintln!("view: {} frames presented, last at {w}x{h}", s.presented);
    }
    Ok(())
}

struct App {
    args: Args,
    modes: Vec<UvMode>,
    path: FlightPath,
    /// Exit after this many presented frames.
    exit_after: Option<u64>,
    state: Option<ViewState>,
    error: Option<anyhow::Error>,
}

struct ViewState {
    window: Arc<Window>,
    presenter: Presenter,
    scene: StoreRenderer,
    cam: FlyCamera,
    fov_y: f64,
    keys: HashSet<KeyCode>,
    dragging: bool,
    cursor: Option<(f64, f64)>,
    /// Mouse captured for mouse look, and how.
    captured: Option<CursorGrabMode>,
    /// The window has no area (minimized): nothing is rendered.
    minimized: bool,
    mode: usize,
    overlay: Overlay,
    last: Instant,
    report: FrameReport,
    /// Frames presented / redraws attempted.
    presented: u64,
    attempts: u64,
    smoke: bool,
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
            .with_resizable(true);
        let window = Arc::new(el.create_window(attrs).context("cannot create a window")?);
        let size = window.inner_size();
        let (w, h) = (size.width.max(1), size.height.max(1));
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_with_display_handle_from_env(
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
        let ctx = GpuContext::from_adapter(adapter)?;
        eprintln!("adapter: {}", ctx.describe());
        let presenter = Presenter::new(surface, &ctx.adapter, &ctx.device, w, h)?;
        // the best texture the store has (photo, else reparameterized, else ortho)
        let mode = self.modes.len() - 1;
        let opts = SceneOptions {
            sse_px: self.args.sse,
            uv_mode: self.modes[mode],
            geomorph: GeomorphOptions {
                enabled: self.args.geomorph,
                ..Default::default()
            },
            ..Default::default()
        };
        let scene = StoreRenderer::open_with_context(&self.args.store, ctx, w, h, opts)?;
        let k = &self.path.keys[0];
        let (p, t) = (DVec3::from(k.position), DVec3::from(k.look_at));
        let r = &scene.store().manifest.cells;
        let extent = r
            .iter()
            .filter(|c| c.level == 0)
            .map(|c| {
                (DVec3::from(c.bbox_max) - DVec3::from(c.bbox_min))
                    .truncate()
                    .length()
            })
            .fold(0.0, f64::max);
        // Cross the terrain in about 30 s at base speed.
        let cam = FlyCamera::look_at(p, t, (extent / 30.0).max(1.0));
        Ok(ViewState {
            window,
            presenter,
            scene,
            cam,
            fov_y: self.path.fov_y_deg.to_radians(),
            keys: HashSet::new(),
            dragging: false,
            cursor: None,
            captured: None,
            minimized: false,
            mode,
            overlay: Overlay::None,
            last: Instant::now(),
            report: FrameReport::default(),
            presented: 0,
            attempts: 0,
            smoke: self.args.smoke_test,
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
            fast: self.keys.contains(&KeyCode::ShiftLeft)
                || self.keys.contains(&KeyCode::ShiftRight),
        }
    }

    fn note(&self, what: &str) {
        if self.smoke {
            eprintln!("view: {what}");
        }
    }

    /// Captures the mouse for mouse look, or releases it.
    fn toggle_capture(&mut self) {
        if self.captured.is_some() {
            release(&self.window);
            self.captured = None;
            self.note("mouse released");
        } else {
            self.dragging = false;
            self.captured = capture(&self.window);
            match self.captured {
                Some(m) => self.note(&format!("mouse captured ({m:?})")),
                None => {
                    eprintln!("note: this window system cannot capture the mouse; drag to look");
                    self.note("mouse capture unavailable");
                }
            }
        }
    }

    fn toggle_geomorph(&mut self) {
        let on = !self.scene.options().geomorph.enabled;
        self.scene.set_geomorph(on);
        self.note(&format!("geomorphing {}", if on { "on" } else { "off" }));
    }

    /// Handles a key press; `Ok(false)` asks to quit.
    fn key(&mut self, code: KeyCode, modes: &[UvMode]) -> anyhow::Result<bool> {
        match code {
            KeyCode::Escape if self.captured.is_some() => self.toggle_capture(),
            KeyCode::Escape => return Ok(false),
            KeyCode::Tab => self.toggle_capture(),
            KeyCode::KeyG => self.toggle_geomorph(),
            KeyCode::KeyL | KeyCode::KeyH | KeyCode::KeyP => {
                let o = match code {
                    KeyCode::KeyL => Overlay::Levels,
                    KeyCode::KeyH => Overlay::Stretch,
                    _ => Overlay::PhotoShare,
                };
                self.overlay = if self.overlay == o { Overlay::None } else { o };
                self.scene.set_mode(modes[self.mode], self.overlay);
            }
            KeyCode::KeyM => {
                self.mode = (self.mode + 1) % modes.len();
                self.scene.set_mode(modes[self.mode], self.overlay);
            }
            KeyCode::Equal | KeyCode::NumpadAdd => {
                self.scene
                    .set_sse(adjust_sse(self.scene.options().sse_px, 1))?;
            }
            KeyCode::Minus | KeyCode::NumpadSubtract => {
                self.scene
                    .set_sse(adjust_sse(self.scene.options().sse_px, -1))?;
            }
            _ => {}
        }
        Ok(true)
    }

    /// The window's new inner size: reconfigures the surface and the render target.
    fn resize(&mut self, width: u32, height: u32) -> anyhow::Result<()> {
        if width == 0 || height == 0 {
            self.minimized = true;
            return Ok(());
        }
        self.minimized = false;
        if (width, height) == self.scene.size() {
            return Ok(());
        }
        self.presenter
            .resize(&self.scene.gpu().device, width, height);
        self.scene.resize(width, height)?;
        self.note(&format!(
            "resized to {width}x{height} (surface and render target)"
        ));
        Ok(())
    }

    /// The smoke test's scripted steps, after frame `n` was presented.
    fn script(&mut self, n: u64) {
        match n {
            1 => {
                let (w, h) = self.scene.size();
                let want = winit::dpi::PhysicalSize::new((w * 3 / 4).max(64), (h * 3 / 4).max(64));
                self.note(&format!("requesting {}x{}", want.width, want.height));
                if let Some(now) = self.window.request_inner_size(want) {
                    // Applied at once on some platforms (no Resized event follows).
                    if let Err(e) = self.resize(now.width, now.height) {
                        eprintln!("error: {e:#}");
                    }
                }
            }
            3 | 5 => self.toggle_capture(),
            4 => self.toggle_geomorph(),
            _ => {}
        }
    }

    /// Renders and presents a frame; returns whether one was presented.
    fn redraw(&mut self, modes: &[UvMode]) -> anyhow::Result<bool> {
        let now = Instant::now();
        let dt = (now - self.last).as_secs_f64().min(0.25);
        self.last = now;
        if self.minimized {
            return Ok(false);
        }
        self.attempts += 1;
        self.cam.step(self.input(), dt);
        let (w, h) = self.scene.size();
        let model = self.cam.model(w, h, self.fov_y);
        self.report = self.scene.frame(&model, false)?;
        let img = self.scene.read_rgba()?;
        let gpu = self.scene.gpu();
        if !self.presenter.present(&gpu.device, &gpu.queue, img) {
            return Ok(false);
        }
        self.presented += 1;
        let r = &self.report;
        let ov = match self.overlay {
            Overlay::None => "",
            Overlay::Levels => " + levels",
            Overlay::Stretch => " + stretch",
            Overlay::PhotoShare => " + photo share",
        };
        self.window.set_title(&format!(
            "cliffmap view — {:.1} ms ({:.1} fps), {} cells, {} triangles, {}{}{}, SSE {:.3} px{}",
            r.frame_ms,
            if dt > 0.0 { 1.0 / dt } else { 0.0 },
            r.drawn,
            r.triangles,
            mode_name(modes[self.mode]),
            ov,
            if self.scene.options().geomorph.enabled {
                ", geomorph"
            } else {
                ""
            },
            self.scene.options().sse_px,
            if self.captured.is_some() {
                " — mouse captured (Tab/Esc releases)"
            } else {
                ""
            },
        ));
        Ok(true)
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

    fn device_event(&mut self, _el: &ActiveEventLoop, _id: DeviceId, event: DeviceEvent) {
        let Some(s) = self.state.as_mut() else {
            return;
        };
        // Raw motion: works with a locked cursor (and a confined one).
        if let (DeviceEvent::MouseMotion { delta }, Some(_)) = (event, s.captured) {
            s.cam.look(delta.0, delta.1, LOOK_RAD_PER_PX);
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
            WindowEvent::Resized(size) => s.resize(size.width, size.height),
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
            WindowEvent::MouseInput {
                state,
                button: MouseButton::Left,
                ..
            } => {
                s.dragging = state == ElementState::Pressed && s.captured.is_none();
                Ok(())
            }
            WindowEvent::MouseInput {
                state: ElementState::Pressed,
                button: MouseButton::Right,
                ..
            } => {
                s.toggle_capture();
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
                if s.captured.is_some() {
                    s.toggle_capture();
                }
                Ok(())
            }
            WindowEvent::RedrawRequested => {
                let r = s.redraw(&self.modes);
                if let Ok(true) = r
                    && s.smoke
                {
                    s.script(s.presented);
                }
                match self.exit_after {
                    Some(n) if s.presented >= n || s.attempts >= 20 * n => el.exit(),
                    _ => s.window.request_redraw(),
                }
                r.map(|_| ())
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
            move |k: &str| {
                pairs
                    .iter()
                    .find(|(n, _)| *n == k)
                    .map(|(_, v)| v.to_string())
            }
        };
        if cfg!(all(unix, not(target_os = "macos"))) {
            assert!(!display_available(env(&[])));
            assert!(!display_available(env(&[("DISPLAY", " ")])));
            assert!(display_available(env(&[("DISPLAY", ":0")])));
            assert!(display_available(env(&[("WAYLAND_DISPLAY", "wayland-0")])));
        }
    }
}
