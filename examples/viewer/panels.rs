//! The window: eframe (egui on the same wgpu device), a side panel per scene whose widgets edit
//! fieldkit's settings structs in place, and the scene drawn into a texture egui shows.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use eframe::egui;
use egui::{Slider, Ui};
use fieldkit::gpu::{PipelineCache, Profiler, Readback};
use fieldkit::view::Targets;
use glam::{Vec2, Vec3};

use super::scene_panels::{
    actor_panel, distance_panel, ocean_panel, volume_panel, voxelizer_panel,
};
use super::scenes::{self, COLOUR, DEPTH, NAMES, Saved, Scenes};
use super::widgets::{
    ERROR_RED, History, draw_legends, file_row, group_totals, one_line, remember, scene_row,
    side_panel,
};
use super::{Args, draw_frame, frame_time, read_colour, save_png};

type PassTimes = (Vec<(String, f64)>, f64);

struct Viewer {
    saved: Saved,
    scene: usize,
    scenes: Scenes,
    targets: Option<([u32; 2], Targets, egui::TextureId)>,
    profiler: Option<Profiler>,
    reading: Option<Readback<PassTimes>>,
    passes: PassTimes,
    /// Every pass read back so far, its time in the last frame it ran in and that frame's
    /// count of passes read: passes that run only on a change (the 2D tool's methods, a new
    /// voxelization) stay listed with their cost.
    seen: Vec<(String, f64, u64)>,
    /// Pass reads so far.
    reads: u64,
    stats: Vec<String>,
    error: Option<String>,
    /// The last Save/Load's outcome (or the pipeline cache's), and whether it failed.
    note: Option<(String, bool)>,
    settings_path: String,
    /// The settings as they were after each finished change, for Undo.
    history: History,
    /// The last frame drawn without an error, shown under the error's overlay while one stands.
    good: Option<wgpu::Texture>,
    /// Where the 2D tool's stroke was last frame (texels), while a button is held over it.
    stroke_from: Option<[u32; 2]>,
    /// The side panel is shown (F2 toggles it).
    panel_open: bool,
    /// "Defaults" was clicked: asking whether to reset the scene.
    confirm_defaults: bool,
    start: Instant,
    last: Instant,
    frame_ms: f64,
    /// CPU time to record and submit the scene's frame (smoothed), ms.
    record_ms: f64,
    drawn: u32,
    vsync: bool,
    /// `--frames N --screenshot FILE`: draw N frames at fixed steps, save, close.
    shot: Option<(u32, PathBuf)>,
    /// fieldkit's pipelines kept between launches (saved after the first frames of each scene
    /// and at exit).
    pipeline_cache: Option<PipelineCache>,
}

/// Open the window and run until it closes.
pub fn run_window(args: Args, saved: Saved, load_error: Option<String>) -> Result<(), String> {
    let mut wgpu_options = eframe::egui_wgpu::WgpuConfiguration::default();
    if let eframe::egui_wgpu::WgpuSetup::CreateNew(new) = &mut wgpu_options.wgpu_setup {
        // Timestamp queries where the adapter has them: the panel shows per-pass GPU time.
        let base = new.device_descriptor.clone();
        new.device_descriptor = Arc::new(move |adapter| {
            let mut d = base(adapter);
            // A pipeline cache where the adapter keeps one: a second launch does not compile.
            // Indirect draws from a first instance: the ocean's patches chosen on the GPU.
            d.required_features |= adapter.features()
                & (wgpu::Features::TIMESTAMP_QUERY
                    | wgpu::Features::PIPELINE_CACHE
                    | wgpu::Features::INDIRECT_FIRST_INSTANCE);
            d
        });
    }
    // `--size WxH`: the scene's part of the window (the settings panel sits beside it).
    let [w, h] = args.size;
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_inner_size([w as f32 + 340.0, h as f32 + 16.0])
            .with_title("fieldkit viewer"),
        wgpu_options,
        ..Default::default()
    };
    let scene = args
        .scene
        .as_deref()
        .and_then(|s| NAMES.iter().position(|n| *n == s))
        .unwrap_or(0);
    let cache_dir = args.window_pipeline_cache();
    let shot = match (args.frames, args.screenshot) {
        (Some(n), Some(p)) => Some((n.max(1), p)),
        (None, Some(p)) => Some((1, p)),
        _ => None,
    };
    let settings_path = args
        .settings
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "viewer.ron".into());
    eframe::run_native(
        "fieldkit viewer",
        options,
        Box::new(move |cc| {
            let rs = cc
                .wgpu_render_state
                .as_ref()
                .ok_or("eframe started without wgpu")?;
            let profiler = Profiler::new(&rs.device, &rs.queue, 256);
            // A cache that cannot be read is a note, not a reason to stop: pipelines are then
            // compiled as without one.
            let (pipeline_cache, cache_note) = match &cache_dir {
                Some(dir) => match PipelineCache::open(&rs.device, &rs.adapter.get_info(), dir) {
                    Ok(c) => (c, None),
                    Err(e) => (None, Some(format!("pipeline cache {}: {e}", dir.display()))),
                },
                None => (None, None),
            };
            let saved_for_history = saved.clone();
            Ok(Box::new(Viewer {
                saved,
                scene,
                scenes: Scenes::new(),
                targets: None,
                profiler,
                reading: None,
                passes: (Vec::new(), 0.0),
                seen: Vec::new(),
                reads: 0,
                stats: Vec::new(),
                error: load_error.map(|e| format!("settings: {e}")),
                note: cache_note.map(|n| (n, true)),
                settings_path,
                history: History::new(&saved_for_history),
                good: None,
                stroke_from: None,
                panel_open: true,
                confirm_defaults: false,
                start: Instant::now(),
                last: Instant::now(),
                frame_ms: 0.0,
                record_ms: 0.0,
                drawn: 0,
                vsync: true,
                shot,
                pipeline_cache,
            }))
        }),
    )
    .map_err(|e| e.to_string())
}

impl eframe::App for Viewer {
    fn on_exit(&mut self) {
        if let Some(cache) = &self.pipeline_cache
            && let Err(e) = cache.save()
        {
            eprintln!("viewer: saving the pipeline cache: {e}");
        }
    }

    fn ui(&mut self, ui: &mut Ui, frame: &mut eframe::Frame) {
        let Some(rs) = frame.wgpu_render_state().cloned() else {
            return;
        };
        let now = Instant::now();
        self.frame_ms = 0.9 * self.frame_ms + 0.1 * (now - self.last).as_secs_f64() * 1e3;
        self.last = now;
        // F2, the panel's own "hide" button or dragging its edge closed hides it; F2, the
        // "settings" button or dragging the edge back shows it.
        if ui
            .ctx()
            .input_mut(|i| i.consume_key(egui::Modifiers::NONE, egui::Key::F2))
        {
            self.panel_open = !self.panel_open;
        }
        let mut open = self.panel_open;
        egui::Panel::left("settings")
            .resizable(true)
            .default_size(330.0)
            .show_collapsible(ui, &mut open, |ui| {
                let scene = self.scene_name();
                let this = std::cell::RefCell::new(&mut *self);
                side_panel(
                    ui,
                    scene,
                    |ui| this.borrow_mut().pinned(ui),
                    |ui| this.borrow_mut().scene_settings(ui, frame),
                );
            });
        self.panel_open &= open;
        if !self.panel_open {
            egui::Area::new(egui::Id::unique("show settings"))
                .fixed_pos(egui::pos2(8.0, 8.0))
                .show(ui.ctx(), |ui| {
                    if ui.button("show settings").on_hover_text("F2").clicked() {
                        self.panel_open = true;
                    }
                });
        }
        egui::CentralPanel::default().show(ui, |ui| self.central(ui, &rs));
        // A change is one undo step once it is finished: no drag, no field being typed in.
        let ctx = ui.ctx().clone();
        let interacting = ctx.egui_is_using_pointer() || ctx.memory(|m| m.focused().is_some());
        self.history.settle(&self.saved, interacting);
        if ctx.input_mut(|i| i.consume_key(egui::Modifiers::COMMAND, egui::Key::Z))
            && let Some(s) = self.history.undo(&self.saved)
        {
            self.saved = s;
        }
        ctx.request_repaint();
    }
}

impl Viewer {
    fn scene_name(&self) -> &'static str {
        NAMES[self.scene]
    }

    /// The top of the side panel, the same height whatever it shows.
    fn pinned(&mut self, ui: &mut Ui) {
        ui.horizontal(|ui| {
            ui.heading("fieldkit viewer");
            if ui
                .small_button("hide")
                .on_hover_text("F2: hide and show the panel")
                .clicked()
            {
                self.panel_open = false;
            }
        });
        scene_row(ui, &mut self.scene);
        ui.horizontal(|ui| file_row(ui, &mut self.settings_path, &mut self.saved, &mut self.note));
        ui.horizontal(|ui| {
            if ui
                .add_enabled(self.history.can_undo(), egui::Button::new("Undo"))
                .on_hover_text("the last change (Ctrl+Z)")
                .clicked()
                && let Some(s) = self.history.undo(&self.saved)
            {
                self.saved = s;
            }
            if self.confirm_defaults {
                let scene = self.scene_name();
                ui.label(format!("reset {scene}?"));
                if ui.button("yes").clicked() {
                    self.saved.reset_scene(scene);
                    self.confirm_defaults = false;
                }
                if ui.button("no").clicked() {
                    self.confirm_defaults = false;
                }
            } else if ui
                .button("Defaults")
                .on_hover_text("this scene's settings and camera back to their defaults")
                .clicked()
            {
                self.confirm_defaults = true;
            }
        });
        // A note (saved, loaded) in grey, a failed load in red: one line, always there.
        let (note, failed) = self
            .note
            .as_ref()
            .map_or(("", false), |(n, f)| (n.as_str(), *f));
        let colour = if failed {
            ERROR_RED
        } else {
            ui.visuals().weak_text_color()
        };
        one_line(ui, note, colour);
        ui.separator();
        // Cost and accuracy: the scene's CPU and GPU time a frame side by side, each number of
        // fixed width so that nothing below moves as they change.
        // The passes' sum beside the frame's GPU time first to last (the gaps between passes
        // are the difference).
        let sum = self.passes.0.iter().map(|p| p.1).sum::<f64>() + 0.0; // an empty sum is −0
        let gpu = match self.profiler {
            Some(_) => format!("Σ {sum:7.3} of {:7.3} ms", self.passes.1),
            None => "     — ms".into(),
        };
        ui.monospace(format!("CPU record+submit {:7.3} ms", self.record_ms));
        ui.monospace(format!("GPU passes {gpu}"));
        ui.monospace(format!(
            "frame interval    {:7.2} ms | {:5.0} fps",
            self.frame_ms,
            1e3 / self.frame_ms.max(1e-3)
        ));
        if self.scene_name() == "distance2d" {
            // What each compared method cost, the last time it ran (the field is computed
            // when the settings change, not every frame).
            let line = group_totals(&self.seen)
                .iter()
                .map(|(g, ms)| format!("{g} {ms:.3}"))
                .collect::<Vec<_>>()
                .join(" | ");
            let line = if line.is_empty() {
                String::new()
            } else {
                format!("GPU ms by method: {line}")
            };
            one_line(ui, &line, ui.visuals().text_color());
        }
        if self.profiler.is_some() {
            egui::CollapsingHeader::new("per pass")
                .default_open(false)
                .show(ui, |ui| {
                    for (name, ms, read) in &self.seen {
                        let when = if *read == self.reads {
                            ""
                        } else {
                            " (an earlier frame)"
                        };
                        ui.label(format!("{name}: {ms:.3} ms{when}"));
                    }
                });
        } else {
            ui.label("no timestamp queries on this adapter: CPU frame time only");
        }
        // The scene's numbers in STAT_LINES lines, blank ones kept, so the panel keeps its
        // height as they come and go.
        for i in 0..STAT_LINES {
            let line = self.stats.get(i).map_or("", String::as_str);
            one_line(ui, line, ui.visuals().text_color());
        }
        one_line(ui, self.error.as_deref().unwrap_or(""), ERROR_RED);
    }

    /// The camera and the scene's own settings, beneath the pinned top.
    fn scene_settings(&mut self, ui: &mut Ui, frame: &mut eframe::Frame) {
        // The 2D tool has no camera to turn.
        if self.scene_name() != "distance2d" {
            self.camera_panel(ui, frame);
        }
        ui.separator();
        // The control the frame's error came from, marked in red.
        let name = NAMES[self.scene];
        let bad = self
            .error
            .as_ref()
            .and_then(|_| self.scenes.culprit(name, &self.saved));
        let s = &mut self.saved;
        match name {
            "actor" => actor_panel(ui, &mut s.actor, bad),
            "ocean" => ocean_panel(ui, &mut s.ocean, bad),
            "volume" => volume_panel(ui, &mut s.volume, bad),
            "distance2d" => distance_panel(ui, &mut s.distance, bad),
            "voxelizer" => voxelizer_panel(ui, &mut s.voxelizer, bad),
            _ => {
                ui.label(
                    "The island is the actor scene's field and march: its settings are \
                     edited there. The sea and the cloud:",
                );
                ocean_panel(ui, &mut s.ocean, bad);
                volume_panel(ui, &mut s.volume, bad);
            }
        }
    }

    fn camera_panel(&mut self, ui: &mut Ui, frame: &mut eframe::Frame) {
        let i = self.scene;
        let c = &mut self.saved.cameras[i];
        ui.label("camera: drag to turn, scroll to zoom; fly: W/A/S/D/Q/E");
        ui.horizontal(|ui| {
            ui.checkbox(&mut c.fly, "fly");
            ui.checkbox(&mut c.reversed_z, "reversed Z");
            if ui.checkbox(&mut self.vsync, "vsync").changed() {
                let mut config = frame
                    .wgpu_surface_config()
                    .unwrap_or(eframe::egui_wgpu::SurfaceConfig::LOW_LATENCY);
                config.present_mode = if self.vsync {
                    wgpu::PresentMode::AutoVsync
                } else {
                    wgpu::PresentMode::AutoNoVsync
                };
                frame.set_wgpu_surface_config(config);
            }
            if ui.button("reset").clicked() {
                *c = scenes::default_camera(NAMES[i]);
            }
        });
        ui.add(Slider::new(&mut c.fov, 0.2..=2.0).text("vertical field of view (rad)"));
    }

    fn central(&mut self, ui: &mut Ui, rs: &eframe::egui_wgpu::RenderState) {
        let avail = ui.available_size();
        let ppp = ui.ctx().pixels_per_point();
        let size = [
            ((avail.x * ppp) as u32).clamp(16, 4096),
            ((avail.y * ppp) as u32).clamp(16, 4096),
        ];
        let (device, queue) = (&rs.device, &rs.queue);
        if self.targets.as_ref().map(|t| t.0) != Some(size) {
            let targets = Targets::new(device, size, COLOUR, DEPTH);
            // The size is clamped to 16–4096 above, within every device's 2D textures; were
            // it refused, the frame's own march would make the images instead.
            if let Err(e) = self.scenes.resized(device, size) {
                eprintln!("viewer: images for {size:?} not made ahead: {e}");
            }
            let mut r = rs.renderer.write();
            let id = match &self.targets {
                Some((_, _, id)) => {
                    r.update_egui_texture_from_wgpu_texture(
                        device,
                        &targets.colour_view,
                        wgpu::FilterMode::Nearest,
                        *id,
                    );
                    *id
                }
                None => r.register_native_texture(
                    device,
                    &targets.colour_view,
                    wgpu::FilterMode::Nearest,
                ),
            };
            self.targets = Some((size, targets, id));
        }
        let id = self.targets.as_ref().expect("set above").2;
        // Time: fixed steps when taking a screenshot, held at the last step asked for while
        // the scene settles (as the offscreen render holds it, so the two match); else the
        // clock.
        let time = match &self.shot {
            Some((n, _)) => frame_time(self.drawn.min(n.saturating_sub(1))),
            None => self.start.elapsed().as_secs_f32(),
        };
        // Take finished pass times; time this frame when no read is in flight.
        if let Some(r) = &mut self.reading
            && let Some(t) = r.try_take()
        {
            self.reading = None;
            if let Ok(t) = t {
                self.reads += 1;
                remember(&mut self.seen, &t.0, self.reads);
                self.passes = t;
            }
        }
        let profile = self.reading.is_none();
        let targets = &self.targets.as_ref().expect("set above").1;
        let recording = Instant::now();
        let (report, _) = draw_frame(
            device,
            queue,
            &mut self.scenes,
            &self.saved,
            NAMES[self.scene],
            targets,
            size,
            time,
            self.drawn,
            self.profiler.as_mut().filter(|_| profile),
        );
        let record_ms = recording.elapsed().as_secs_f64() * 1e3;
        self.record_ms = 0.9 * self.record_ms + 0.1 * record_ms;
        if profile && let Some(p) = self.profiler.as_mut() {
            let mut enc = device.create_command_encoder(&Default::default());
            p.resolve(&mut enc);
            queue.submit([enc.finish()]);
            self.reading = Some(p.read(device, queue));
        }
        self.stats = report.stats;
        self.error = report.error.map(|e| e.to_string());
        self.keep_or_restore_good_frame(device, queue, size);
        self.drawn += 1;
        let image = egui::Image::new(egui::load::SizedTexture::new(
            id,
            egui::vec2(size[0] as f32 / ppp, size[1] as f32 / ppp),
        ))
        .sense(egui::Sense::click_and_drag());
        let response = ui.add(image);
        if let Some(e) = &self.error {
            // The last good frame stays beneath; the error over its top, where it is read.
            let font = egui::FontId::proportional(14.0);
            let galley = ui.painter().layout(
                format!("{e}\n(the last frame drawn without an error)"),
                font,
                ERROR_RED,
                response.rect.width() - 24.0,
            );
            let at = response.rect.left_top() + egui::vec2(12.0, 12.0);
            let back = egui::Rect::from_min_size(at, galley.size()).expand(6.0);
            ui.painter()
                .rect_filled(back, 4.0, egui::Color32::from_black_alpha(200));
            ui.painter().galley(at, galley, ERROR_RED);
        }
        draw_legends(
            ui.ctx(),
            response.rect,
            &self.saved.legends(NAMES[self.scene]),
        );
        self.input(ui, &response, size);
        if let Some((n, path)) = &self.shot
            && self.drawn >= *n
            && !self.scenes.busy(NAMES[self.scene], &self.saved)
        {
            let targets = &self.targets.as_ref().expect("set above").1;
            let result = read_colour(device, queue, targets)
                .map_err(|e| e.to_string())
                .and_then(|px| save_png(path, &px, size));
            match result {
                Ok(()) => println!("wrote {}", path.display()),
                Err(e) => eprintln!("{e}"),
            }
            if let Some(e) = &self.error {
                println!("error: {e}");
            }
            ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
            self.shot = None;
        }
    }

    /// After a frame without an error, keep a copy of it; after one with an error, put the
    /// last kept frame back into the target the panel shows.
    fn keep_or_restore_good_frame(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        size: [u32; 2],
    ) {
        let colour = &self.targets.as_ref().expect("made before drawing").1.colour;
        let extent = colour.size();
        let mut enc = device.create_command_encoder(&Default::default());
        if self.error.is_none() {
            if self.good.as_ref().map(|g| g.size()) != Some(extent) {
                self.good = Some(fieldkit::gpu::texture(
                    device,
                    "viewer last good frame",
                    [size[0], size[1], 1],
                    wgpu::TextureDimension::D2,
                    COLOUR,
                    wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::COPY_SRC,
                ));
            }
            let good = self.good.as_ref().expect("made above");
            enc.copy_texture_to_texture(colour.as_image_copy(), good.as_image_copy(), extent);
        } else if let Some(good) = self.good.as_ref().filter(|g| g.size() == extent) {
            enc.copy_texture_to_texture(good.as_image_copy(), colour.as_image_copy(), extent);
        }
        queue.submit([enc.finish()]);
    }

    fn input(&mut self, ui: &Ui, response: &egui::Response, size: [u32; 2]) {
        let i = self.scene;
        if NAMES[i] == "distance2d" {
            // Left button draws seeds, right erases (a click or a drag): a drag is a stroke,
            // joined to where the pointer was last frame.
            let d = &mut self.saved.distance;
            let erase = ui.input(|inp| inp.pointer.button_down(egui::PointerButton::Secondary))
                || response.secondary_clicked();
            let at = response.interact_pointer_pos().and_then(|pos| {
                let r = response.rect;
                let uv = (pos - r.min) / r.size();
                let [x0, y0, x1, y1] = scenes::field_rect(size, d.size);
                let fx = (uv.x - x0) / (x1 - x0);
                let fy = (uv.y - y0) / (y1 - y0);
                ((0.0..1.0).contains(&fx) && (0.0..1.0).contains(&fy)).then(|| {
                    [
                        (fx * d.size[0] as f32) as u32,
                        (fy * d.size[1] as f32) as u32,
                    ]
                })
            });
            match at {
                Some(at) => {
                    d.paint_stroke(self.stroke_from.unwrap_or(at), at, erase);
                    self.stroke_from = Some(at);
                }
                None => self.stroke_from = None,
            }
            return;
        }
        let c = &mut self.saved.cameras[i];
        if response.dragged() {
            let d = response.drag_delta();
            c.drag(Vec2::new(d.x, d.y));
        }
        if response.hovered() {
            let scroll = ui.input(|inp| inp.smooth_scroll_delta.y);
            c.zoom(scroll);
        }
        if c.fly {
            let dt = ui.input(|inp| inp.stable_dt).min(0.1);
            let speed = c.distance.max(0.5) * dt;
            let mut v = Vec3::ZERO;
            ui.input(|inp| {
                for (key, dir) in [
                    (egui::Key::W, Vec3::Z),
                    (egui::Key::S, -Vec3::Z),
                    (egui::Key::D, Vec3::X),
                    (egui::Key::A, -Vec3::X),
                    (egui::Key::E, Vec3::Y),
                    (egui::Key::Q, -Vec3::Y),
                ] {
                    if inp.key_down(key) {
                        v += dir;
                    }
                }
            });
            c.fly_by(v * speed);
        }
    }
}

/// Lines of scene numbers the pinned panel keeps room for.
const STAT_LINES: usize = 4;
