//! fieldkit in a real render loop: a winit window whose frame draws the application's own scene
//! (a checkered floor, with its own pipeline and depth buffer), then the animated metaball
//! surface raymarched into the same colour and depth targets, so the two occlude each other.
//!
//! ```sh
//! cargo run --release --example window
//! cargo run --example window -- --frames 5 --screenshot shot.png   # draw 5 frames, save the last
//! ```
//!
//! The device is the application's: default limits, no optional features. With `--frames N`
//! the animation advances 1/60 s a frame (not by the clock), so the last frame can be compared
//! with [`render_offscreen`], which `tests/window.rs` does under Xvfb.

use std::sync::Arc;

use fieldkit::Error;
use fieldkit::metaball::{Metaballs, Settings, animate, packed_grid};
use fieldkit::metaball::{RaymarchSettings, Raymarcher};
use fieldkit::view::View;
use glam::{Mat4, Vec3};
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

/// Window size.
pub const SIZE: [u32; 2] = [320, 200];
/// Depth format of the frame.
pub const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
const EDGE: f32 = 1.0;

/// The application's floor: a checkered square at y = −1.6 (its own WGSL, not fieldkit's).
const FLOOR_WGSL: &str = r#"
struct Camera { view_proj: mat4x4<f32> }
@group(0) @binding(0) var<uniform> camera: Camera;

struct Out { @builtin(position) position: vec4<f32>, @location(0) world: vec3<f32> }

@vertex
fn vs(@builtin(vertex_index) i: u32) -> Out {
    var corners = array(vec2(-1.0, -1.0), vec2(1.0, -1.0), vec2(1.0, 1.0),
                        vec2(-1.0, -1.0), vec2(1.0, 1.0), vec2(-1.0, 1.0));
    let world = vec3(corners[i].x * 12.0, -1.6, corners[i].y * 12.0);
    return Out(camera.view_proj * vec4(world, 1.0), world);
}

@fragment
fn fs(v: Out) -> @location(0) vec4<f32> {
    let k = (i32(floor(v.world.x)) + i32(floor(v.world.z))) & 1;
    let g = select(0.30, 0.55, k == 0);
    return vec4(g, g, g * 1.1, 1.0);
}
"#;

/// The frame's scene: the application's floor and fieldkit's metaballs.
pub struct Scene {
    floor: wgpu::RenderPipeline,
    camera: wgpu::Buffer,
    floor_group: wgpu::BindGroup,
    balls: Metaballs,
    instances: fieldkit::metaball::Instances,
    marcher: Raymarcher,
    base: Vec<glam::Vec4>,
    settings: Settings,
}

impl Scene {
    /// Pipelines for a colour target of `format` and a [`DEPTH`] target.
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        format: wgpu::TextureFormat,
    ) -> Result<Self, Error> {
        let floor = fieldkit::harness::wgsl_pipeline(
            device,
            "floor",
            FLOOR_WGSL,
            format,
            Some(wgpu::DepthStencilState {
                format: DEPTH,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::Less),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            &[],
            Default::default(),
        );
        let camera = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("floor camera"),
            size: 64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let floor_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("floor camera"),
            layout: &floor.get_bind_group_layout(0),
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: camera.as_entire_binding(),
            }],
        });
        let base = packed_grid([4, 3, 3], EDGE)?;
        let balls = Metaballs::new(device)?;
        let instances = balls.upload(device, queue, &base)?;
        let marcher = Raymarcher::new(device, queue, format, DEPTH, false)?;
        Ok(Self {
            floor,
            camera,
            floor_group,
            balls,
            instances,
            marcher,
            base,
            settings: Settings::default(),
        })
    }

    /// Record one frame at `time` seconds into `colour` and `depth` (both `size`).
    #[allow(clippy::too_many_arguments)]
    pub fn encode(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        colour: &wgpu::TextureView,
        depth: &wgpu::TextureView,
        size: [u32; 2],
        time: f32,
    ) -> Result<(), Error> {
        let proj = glam::camera::rh::proj::directx::perspective(
            0.8,
            size[0] as f32 / size[1] as f32,
            0.1,
            100.0,
        );
        let eye = Vec3::new(4.0, 3.0, 7.0);
        let view = View {
            view_proj: proj
                * glam::camera::rh::view::look_at_mat4(eye, Vec3::new(0.0, -0.5, 0.0), Vec3::Y),
            viewport: size,
            reversed_z: false,
            origin: [0, 0],
        };
        queue.write_buffer(&self.camera, 0, bytemuck::bytes_of(&view.view_proj));
        // The application's pass: clear, then the floor.
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("floor"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: colour,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.12,
                            g: 0.14,
                            b: 0.18,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(fieldkit::gpu::depth_cleared(depth, 1.0)),
                ..Default::default()
            });
            pass.set_pipeline(&self.floor);
            pass.set_bind_group(0, &self.floor_group, &[]);
            pass.draw(0..6, 0..1);
        }
        // fieldkit's: the animated voxels, their field, the raymarched surface, depth-tested
        // against the floor.
        let voxels = animate(&self.base, EDGE, time, 0.5, 0.15);
        self.balls.update(queue, &mut self.instances, &voxels)?;
        if let Some(grid) = self.settings.fit_grid(&voxels, EDGE)? {
            let field = self.balls.encode(
                device,
                encoder,
                &self.instances,
                &grid,
                EDGE,
                &self.settings,
            )?;
            self.marcher.encode(
                device,
                encoder,
                colour,
                depth,
                &field,
                Mat4::IDENTITY,
                &view,
                &RaymarchSettings::default(),
            )?;
        }
        Ok(())
    }
}

fn depth_target(device: &wgpu::Device, [width, height]: [u32; 2]) -> wgpu::TextureView {
    fieldkit::gpu::texture(
        device,
        "depth",
        [width, height, 1],
        wgpu::TextureDimension::D2,
        DEPTH,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    )
    .create_view(&Default::default())
}

/// Copy mip 0 of a 2D RGBA8 or BGRA8 `texture` (with `COPY_SRC`) into RGBA8 rows, blocking.
fn read_rgba(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
) -> Result<Vec<u8>, Error> {
    let bgra = matches!(
        texture.format(),
        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb
    );
    let mut readback = fieldkit::gpu::readback_texture::<[u8; 4]>(device, queue, texture);
    let px = loop {
        if let Some(r) = readback.try_take() {
            break r?;
        }
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| Error::Readback(e.to_string()))?;
    };
    Ok(px
        .into_iter()
        .flat_map(|[a, b, c, d]| if bgra { [c, b, a, d] } else { [a, b, c, d] })
        .collect())
}

/// The frame at `time` drawn into an offscreen `format` target: what the window shows.
pub fn render_offscreen(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    format: wgpu::TextureFormat,
    time: f32,
) -> Result<Vec<u8>, Error> {
    let mut scene = Scene::new(device, queue, format)?;
    let [width, height] = SIZE;
    let target = fieldkit::gpu::texture(
        device,
        "offscreen",
        [width, height, 1],
        wgpu::TextureDimension::D2,
        format,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = depth_target(device, SIZE);
    let mut encoder = device.create_command_encoder(&Default::default());
    let view = target.create_view(&Default::default());
    scene.encode(device, queue, &mut encoder, &view, &depth, SIZE, time)?;
    queue.submit([encoder.finish()]);
    read_rgba(device, queue, &target)
}

/// Seconds of animation at frame `i` of a fixed-step run.
pub fn frame_time(i: u32) -> f32 {
    i as f32 / 60.0
}

struct Gpu {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    config: wgpu::SurfaceConfiguration,
    depth: wgpu::TextureView,
    scene: Scene,
}

/// The surface format the example asks for: a linear 8-bit one when offered (so the screenshot
/// holds the values the shaders wrote), else the first.
pub fn pick_format(formats: &[wgpu::TextureFormat]) -> Option<wgpu::TextureFormat> {
    formats
        .iter()
        .copied()
        .find(|f| {
            matches!(
                f,
                wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
            )
        })
        .or_else(|| formats.first().copied())
}

struct App {
    gpu: Option<Gpu>,
    frames: Option<u32>,
    drawn: u32,
    screenshot: Option<String>,
    started: std::time::Instant,
    result: Result<(), String>,
}

impl App {
    fn open(&mut self, event_loop: &ActiveEventLoop) -> Result<Gpu, String> {
        let attributes = Window::default_attributes()
            .with_title("fieldkit: metaballs over the application's scene")
            .with_inner_size(winit::dpi::PhysicalSize::new(SIZE[0], SIZE[1]))
            .with_resizable(self.frames.is_none());
        let window = Arc::new(
            event_loop
                .create_window(attributes)
                .map_err(|e| e.to_string())?,
        );
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends: wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let surface = instance
            .create_surface(window.clone())
            .map_err(|e| format!("create_surface: {e}"))?;
        let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
            compatible_surface: Some(&surface),
            ..Default::default()
        }))
        .map_err(|e| format!("no adapter can present to this window: {e}"))?;
        eprintln!("adapter: {}", adapter.get_info().name);
        let (device, queue) = pollster::block_on(adapter.request_device(&Default::default()))
            .map_err(|e| e.to_string())?;
        let caps = surface.get_capabilities(&adapter);
        let format = pick_format(&caps.formats).ok_or("the surface offers no format")?;
        let size = window.inner_size();
        let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
        if self.screenshot.is_some() {
            if !caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
                return Err("the surface cannot be copied from; no screenshot possible".into());
            }
            usage |= wgpu::TextureUsages::COPY_SRC;
        }
        let config = wgpu::SurfaceConfiguration {
            usage,
            format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode: wgpu::PresentMode::Fifo,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps.alpha_modes[0],
            view_formats: vec![],
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&device, &config);
        let depth = depth_target(&device, [config.width, config.height]);
        let scene = Scene::new(&device, &queue, format).map_err(|e| e.to_string())?;
        Ok(Gpu {
            window,
            surface,
            device,
            queue,
            config,
            depth,
            scene,
        })
    }

    /// Draw and present one frame; `Ok(true)` when the run is over.
    fn frame(&mut self) -> Result<bool, String> {
        let Some(gpu) = self.gpu.as_mut() else {
            return Ok(false);
        };
        let texture = match gpu.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => {
                // Outdated or lost: configure again and draw next time.
                eprintln!("surface: {other:?}; reconfiguring");
                gpu.surface.configure(&gpu.device, &gpu.config);
                return Ok(false);
            }
        };
        let time = match self.frames {
            Some(_) => frame_time(self.drawn),
            None => self.started.elapsed().as_secs_f32(),
        };
        let view = texture.texture.create_view(&Default::default());
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        let size = [gpu.config.width, gpu.config.height];
        gpu.scene
            .encode(
                &gpu.device,
                &gpu.queue,
                &mut encoder,
                &view,
                &gpu.depth,
                size,
                time,
            )
            .map_err(|e| e.to_string())?;
        gpu.queue.submit([encoder.finish()]);
        self.drawn += 1;
        let last = self.frames.is_some_and(|n| self.drawn >= n);
        if last && let Some(path) = &self.screenshot {
            let rgba =
                read_rgba(&gpu.device, &gpu.queue, &texture.texture).map_err(|e| e.to_string())?;
            image::save_buffer(
                path,
                &rgba,
                size[0],
                size[1],
                image::ExtendedColorType::Rgba8,
            )
            .map_err(|e| format!("{path}: {e}"))?;
            eprintln!(
                "screenshot of frame {} ({:?}): {path}",
                self.drawn - 1,
                gpu.config.format
            );
        }
        gpu.window.pre_present_notify();
        gpu.queue.present(texture);
        Ok(last)
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        if self.gpu.is_some() {
            return;
        }
        match self.open(event_loop) {
            Ok(gpu) => {
                gpu.window.request_redraw();
                self.gpu = Some(gpu);
            }
            Err(e) => {
                self.result = Err(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::Resized(size) => {
                if let Some(gpu) = self.gpu.as_mut()
                    && size.width > 0
                    && size.height > 0
                {
                    gpu.config.width = size.width;
                    gpu.config.height = size.height;
                    gpu.surface.configure(&gpu.device, &gpu.config);
                    gpu.depth = depth_target(&gpu.device, [size.width, size.height]);
                }
            }
            WindowEvent::RedrawRequested => match self.frame() {
                Ok(true) => event_loop.exit(),
                Ok(false) => {
                    if let Some(gpu) = &self.gpu {
                        gpu.window.request_redraw();
                    }
                }
                Err(e) => {
                    self.result = Err(e);
                    event_loop.exit();
                }
            },
            _ => {}
        }
    }
}

fn main() -> std::process::ExitCode {
    let mut args = std::env::args().skip(1);
    let mut app = App {
        gpu: None,
        frames: None,
        drawn: 0,
        screenshot: None,
        started: std::time::Instant::now(),
        result: Ok(()),
    };
    while let Some(arg) = args.next() {
        match arg.as_str() {
            "--frames" => app.frames = args.next().and_then(|n| n.parse().ok()),
            "--screenshot" => app.screenshot = args.next(),
            other => {
                eprintln!("usage: window [--frames N] [--screenshot PATH] (got {other})");
                return std::process::ExitCode::FAILURE;
            }
        }
    }
    if app.screenshot.is_some() && app.frames.is_none() {
        app.frames = Some(5);
    }
    let event_loop = match EventLoop::new() {
        Ok(l) => l,
        Err(e) => {
            eprintln!("error: no window system ({e}); under CI run it with xvfb-run");
            return std::process::ExitCode::FAILURE;
        }
    };
    if let Err(e) = event_loop.run_app(&mut app) {
        eprintln!("error: {e}");
        return std::process::ExitCode::FAILURE;
    }
    match app.result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}
