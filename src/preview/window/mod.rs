//! The interactive preview (`chambre preview --window`): the raster preview
//! (`preview::PreviewRenderer`) drawn into a window through winit, redrawn as keys or the
//! mouse move the film and turn the camera ([`Composer`], `compose`), the figures in the window's
//! title and on the terminal; `s` saves the scene with the composition, to be rendered by the
//! ray tracer.
//!
//! A `--keys` script replays keys after the first frame, as if typed, then closes the window;
//! with `--screenshot` the last frame shown is written out. That is how it runs headless and is
//! tested (under Xvfb, `tests/window.rs`). Shader: `wgsl/preview/present.wgsl`.

mod compose;

pub use compose::{
    ComposeAction, ComposeKey, Composer, DRAG_DEG_PER_PX, Drag, SHIFT_STEP_MM, TURN_STEP_DEG,
};

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use bytemuck::{Pod, Zeroable};
use winit::application::ApplicationHandler;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::keyboard::{Key, NamedKey};
use winit::window::{Window, WindowId};

use crate::error::{Error, Result};
use crate::gpu::GpuContext;
use crate::gpu::kernels::{Access, Binding};
use crate::output::OutputTarget;
use crate::pack::FlatScene;
use crate::preview::renderer::pipeline::{RasterPipeline, buffer_entry, texture_entry};
use crate::preview::{PreviewOptions, PreviewRenderer};
use crate::scene::{Scene, merged_scene_text};

/// What the window is asked to do beside showing the scene.
#[derive(Clone, Debug, Default)]
pub struct WindowOptions {
    /// Keys replayed after the first frame; the window closes after the last.
    pub keys: Vec<ComposeKey>,
    /// Where the last frame shown is written (PNG, EXR or PFM) when the window closes.
    pub screenshot: Option<PathBuf>,
    /// Where `s` saves the composed scene.
    pub save: PathBuf,
    /// How the preview draws (curved shapes' tolerance, mirrors' reflections).
    pub drawing: PreviewOptions,
}

/// What happened in the window.
#[derive(Clone, Debug, Default)]
pub struct WindowReport {
    /// Frames drawn and shown.
    pub frames: u32,
    /// Where `s` saved the scene, each time.
    pub saved: Vec<PathBuf>,
    /// The composition when the window closed, as scene overrides.
    pub overrides: Vec<String>,
}

/// Pixels of a touchpad's scroll taken as one notch of a wheel (winit reports a wheel's turn
/// in notches and a touchpad's in pixels).
const SCROLL_PX_PER_NOTCH: f64 = 40.0;

/// The presentation shader's uniforms (`wgsl/preview/present.wgsl`'s `Present`).
#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct PresentUniforms {
    scale: [f32; 2],
    encode_srgb: u32,
    _pad: u32,
}

/// Opens a window on `scene` (loaded from `path` with `overrides`, flattened as `flat`) and
/// runs until it is closed or its key script ends.
pub fn run(
    path: &Path,
    overrides: &[String],
    scene: &Scene,
    flat: &FlatScene,
    options: WindowOptions,
) -> Result<WindowReport> {
    let screenshot = options
        .screenshot
        .as_deref()
        .map(OutputTarget::prepare)
        .transpose()?;
    let event_loop = EventLoop::new()
        .map_err(|e| Error::Gpu(format!("no window system to open a window on: {e}")))?;
    let mut app = App {
        path: path.to_path_buf(),
        overrides: overrides.to_vec(),
        scene,
        flat,
        composer: Composer::new(&scene.camera),
        script: options.keys.into_iter().rev().collect(),
        scripted: false,
        save: options.save,
        drawing: options.drawing,
        screen: None,
        report: WindowReport::default(),
        error: None,
        cursor: None,
        drag: None,
    };
    app.scripted = !app.script.is_empty();
    event_loop
        .run_app(&mut app)
        .map_err(|e| Error::Gpu(format!("the window's event loop: {e}")))?;
    if let Some(e) = app.error.take() {
        return Err(e);
    }
    if let (Some(target), Some(screen)) = (&screenshot, &app.screen) {
        target.write(&screen.preview.image()?)?;
    }
    app.report.overrides = app.composer.overrides();
    Ok(app.report)
}

/// The window, its surface and what draws into it.
struct Screen {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    config: wgpu::SurfaceConfiguration,
    context: GpuContext,
    preview: PreviewRenderer,
    present: wgpu::RenderPipeline,
    present_layout: wgpu::BindGroupLayout,
    present_uniforms: wgpu::Buffer,
}

struct App<'a> {
    path: PathBuf,
    overrides: Vec<String>,
    scene: &'a Scene,
    flat: &'a FlatScene,
    composer: Composer,
    /// Keys still to replay, the next last.
    script: Vec<ComposeKey>,
    /// A script was given: the window closes when it ends.
    scripted: bool,
    save: PathBuf,
    drawing: PreviewOptions,
    screen: Option<Screen>,
    report: WindowReport,
    error: Option<Error>,
    /// Where the cursor last was in the window (physical pixels), while it is in it.
    cursor: Option<(f64, f64)>,
    /// What the mouse drags while a button is held.
    drag: Option<Drag>,
}

impl ApplicationHandler for App<'_> {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.screen.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(screen) => {
                screen.window.request_redraw();
                self.screen = Some(screen);
                println!("{}", self.composer.figures());
            }
            Err(e) => self.fail(event_loop, e),
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            // winit makes up a press of each key held down when the window gains focus
            // (`is_synthetic`): that key was typed elsewhere, and on a loaded machine a key
            // typed just after the focus moved was applied twice (the window test's film tilt
            // went -3° for two presses).
            WindowEvent::KeyboardInput {
                event,
                is_synthetic: false,
                ..
            } if event.state == ElementState::Pressed => {
                if let Some(key) = compose_key(&event.logical_key) {
                    self.press(event_loop, key);
                }
            }
            WindowEvent::MouseInput { state, button, .. } => {
                self.drag = match (state, button) {
                    (ElementState::Pressed, MouseButton::Left) => Some(Drag::Camera),
                    (ElementState::Pressed, MouseButton::Right) => Some(Drag::Film),
                    (ElementState::Released, _) => None,
                    _ => self.drag,
                };
            }
            WindowEvent::CursorMoved { position, .. } => {
                let last = self.cursor.replace((position.x, position.y));
                if let (Some(drag), Some((x, y))) = (self.drag, last) {
                    let action = self.composer.drag(drag, position.x - x, position.y - y);
                    self.act(event_loop, action);
                }
            }
            // Out of the window the cursor's moves are not seen: its next position in it is
            // not a drag from the last.
            WindowEvent::CursorLeft { .. } => self.cursor = None,
            WindowEvent::MouseWheel { delta, .. } => {
                let (across, notches) = match delta {
                    MouseScrollDelta::LineDelta(x, y) => (f64::from(x), f64::from(y)),
                    MouseScrollDelta::PixelDelta(p) => {
                        (p.x / SCROLL_PX_PER_NOTCH, p.y / SCROLL_PX_PER_NOTCH)
                    }
                };
                let action = self.composer.wheel(across, notches);
                self.act(event_loop, action);
            }
            WindowEvent::Resized(size) => {
                if let Some(screen) = &mut self.screen {
                    screen.config.width = size.width.max(1);
                    screen.config.height = size.height.max(1);
                    screen
                        .surface
                        .configure(&screen.context.device, &screen.config);
                }
            }
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw() {
                    return self.fail(event_loop, e);
                }
                // The script plays one key a frame, so each of its frames is shown.
                match self.script.pop() {
                    Some(key) => self.press(event_loop, key),
                    None if self.scripted => event_loop.exit(),
                    None => {}
                }
            }
            _ => {}
        }
    }
}

impl App<'_> {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: Error) {
        self.error = Some(e);
        event_loop.exit();
    }

    fn press(&mut self, event_loop: &ActiveEventLoop, key: ComposeKey) {
        let action = self.composer.apply(key);
        self.act(event_loop, action);
    }

    /// Does what a key or the mouse asked: draws the composed camera, saves, or closes.
    fn act(&mut self, event_loop: &ActiveEventLoop, action: ComposeAction) {
        match action {
            ComposeAction::Changed => {
                println!("{}", self.composer.figures());
                if let Some(screen) = &mut self.screen {
                    let coarse = screen.preview.coarse_shapes();
                    if let Err(e) = screen.preview.set_camera(&self.composer.camera()) {
                        self.fail(event_loop, e);
                        return;
                    }
                    note_coarse_shapes(&screen.preview, coarse, self.drawing.tolerance_px);
                    screen.window.request_redraw();
                }
            }
            ComposeAction::Save => match self.save_scene() {
                Ok(()) => {
                    println!("saved {}", self.save.display());
                    self.report.saved.push(self.save.clone());
                    if let Some(screen) = &self.screen {
                        screen.window.request_redraw();
                    }
                }
                Err(e) => self.fail(event_loop, e),
            },
            ComposeAction::Quit => event_loop.exit(),
            ComposeAction::Nothing => {
                if let Some(screen) = &self.screen {
                    screen.window.request_redraw();
                }
            }
        }
    }

    /// The scene file with the user's overrides and the composition, written atomically.
    fn save_scene(&self) -> Result<()> {
        let mut overrides = self.overrides.clone();
        overrides.extend(self.composer.overrides());
        let text = merged_scene_text(&self.path, &overrides)?;
        let header = format!(
            "# Composed with `chambre preview --window` from {}: {}.\n\n",
            self.path.display(),
            self.composer.figures()
        );
        OutputTarget::write_beside(&self.save, (header + &text).as_bytes())
    }

    fn open(&self, event_loop: &ActiveEventLoop) -> Result<Screen> {
        let (width, height) = (self.flat.frame.width, self.flat.frame.height);
        let attributes = Window::default_attributes()
            .with_title(title(&self.composer, None))
            .with_inner_size(winit::dpi::PhysicalSize::new(width, height))
            .with_resizable(false);
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| Error::Gpu(format!("opening a window: {e}")))?,
        );
        let context = GpuContext::new()?;
        let surface = context
            .instance
            .create_surface(window.clone())
            .map_err(|e| Error::Gpu(format!("a surface for the window: {e}")))?;
        let size = window.inner_size();
        let mut config = surface
            .get_default_config(&context.adapter, size.width.max(1), size.height.max(1))
            .ok_or_else(|| {
                Error::Gpu(format!(
                    "{} cannot present to this window",
                    context.adapter_name
                ))
            })?;
        // An sRGB format encodes the colour as the PNG output does, where the surface has one.
        let formats = surface.get_capabilities(&context.adapter).formats;
        if let Some(&srgb) = formats.iter().find(|f| f.is_srgb()) {
            config.format = srgb;
        }
        surface.configure(&context.device, &config);
        let mut preview = PreviewRenderer::new(&context, self.scene, self.flat, self.drawing)?;
        preview.set_camera(&self.composer.camera())?;
        note_coarse_shapes(&preview, 0, self.drawing.tolerance_px);
        let (present, present_layout) = present_pipeline(&context, config.format);
        let present_uniforms = context.uniform_buffer(
            "present uniforms",
            bytemuck::bytes_of(&PresentUniforms::zeroed()),
        );
        Ok(Screen {
            window,
            surface,
            config,
            context,
            preview,
            present,
            present_layout,
            present_uniforms,
        })
    }

    /// Draws the preview and shows it.
    fn redraw(&mut self) -> Result<()> {
        let Some(screen) = &mut self.screen else {
            return Ok(());
        };
        let start = Instant::now();
        screen.preview.draw()?;
        let frame = match screen.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(frame)
            | wgpu::CurrentSurfaceTexture::Suboptimal(frame) => frame,
            wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                screen
                    .surface
                    .configure(&screen.context.device, &screen.config);
                screen.window.request_redraw();
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Timeout | wgpu::CurrentSurfaceTexture::Occluded => {
                return Ok(());
            }
            wgpu::CurrentSurfaceTexture::Validation => {
                return Err(Error::Gpu("acquiring the window's next image".into()));
            }
        };
        let image = screen.preview.image_size();
        let uniforms = PresentUniforms {
            scale: [
                image.0 as f32 / screen.config.width as f32,
                image.1 as f32 / screen.config.height as f32,
            ],
            encode_srgb: (!screen.config.format.is_srgb()) as u32,
            _pad: 0,
        };
        let context = &screen.context;
        context
            .queue
            .write_buffer(&screen.present_uniforms, 0, bytemuck::bytes_of(&uniforms));
        let bind_group = context
            .device
            .create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("present"),
                layout: &screen.present_layout,
                entries: &[
                    texture_entry(IMAGE, screen.preview.view()),
                    buffer_entry(PRESENT, &screen.present_uniforms),
                ],
            });
        let view = frame.texture.create_view(&Default::default());
        let mut encoder = context.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(&screen.present);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        context.queue.submit([encoder.finish()]);
        screen.window.pre_present_notify();
        context.queue.present(frame);
        self.report.frames += 1;
        screen
            .window
            .set_title(&title(&self.composer, Some(start.elapsed().as_secs_f64())));
        Ok(())
    }
}

/// The window's title: the composition, and the last frame's time.
fn title(composer: &Composer, seconds: Option<f64>) -> String {
    match seconds {
        Some(s) => format!(
            "chambre preview: {} ({:.1} ms)",
            composer.figures(),
            s * 1e3
        ),
        None => format!("chambre preview: {}", composer.figures()),
    }
}

/// The composing key a pressed key is, if any.
fn compose_key(key: &Key) -> Option<ComposeKey> {
    match key {
        Key::Named(NamedKey::ArrowUp) => Some(ComposeKey::Up),
        Key::Named(NamedKey::ArrowDown) => Some(ComposeKey::Down),
        Key::Named(NamedKey::ArrowLeft) => Some(ComposeKey::Left),
        Key::Named(NamedKey::ArrowRight) => Some(ComposeKey::Right),
        Key::Named(NamedKey::Escape) => Some(ComposeKey::Escape),
        Key::Character(c) => ComposeKey::parse(c),
        _ => None,
    }
}

/// The presentation's shader (`wgsl/preview/present.wgsl`).
const PRESENT_SHADER: &str = include_str!("../../../wgsl/preview/present.wgsl");

/// The preview's image (read by `textureLoad`: a float texture that needs no filtering).
pub const IMAGE: Binding = Binding::new(0, "image", Access::FloatTexture, FRAGMENT);
/// How to draw it into the window (`Present`).
pub const PRESENT: Binding = Binding::new(1, "present", Access::Uniform, FRAGMENT);
const FRAGMENT: wgpu::ShaderStages = wgpu::ShaderStages::FRAGMENT;

/// The presentation: the preview's image drawn into the window with one triangle.
pub const PRESENT_PASS: RasterPipeline = RasterPipeline {
    name: "present",
    source: || PRESENT_SHADER.to_string(),
    vertex: "present_vertex",
    fragment: Some("present_fragment"),
    groups: &[&[IMAGE, PRESENT]],
};

/// The pipeline that shows the preview's float image in the window, and its bind group
/// layout.
fn present_pipeline(
    context: &GpuContext,
    format: wgpu::TextureFormat,
) -> (wgpu::RenderPipeline, wgpu::BindGroupLayout) {
    let device = &context.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("present"),
        source: wgpu::ShaderSource::Wgsl(PRESENT_SHADER.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(PRESENT_PASS.name),
        layout: Some(&PRESENT_PASS.layout(device)),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(PRESENT_PASS.vertex),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: PRESENT_PASS.fragment,
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let layout = pipeline.get_bind_group_layout(0);
    (pipeline, layout)
}

/// Says so when the preview's curved shapes stray further than the tolerance, and their count
/// was `before` (not said again while it stays).
fn note_coarse_shapes(preview: &PreviewRenderer, before: usize, tolerance_px: f64) {
    let now = preview.coarse_shapes();
    if now > 0 && now != before {
        eprintln!("{}", crate::preview::coarse_note(now, tolerance_px));
    }
}
