//! The window: eframe (egui on the same wgpu device), a side panel per scene whose widgets edit
//! fieldkit's settings structs in place, and the scene drawn into a texture egui shows.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

use eframe::egui;
use egui::{ComboBox, DragValue, Slider, Ui};
use fieldkit::gpu::{PipelineCache, Profiler, Readback};
use fieldkit::metaball::{Direct, Output as MarchOutput};
use fieldkit::view::Targets;
use fieldkit::volume::{Mode, Shadow, TransferFunction};
use fieldkit::voxelize::ColourBy;
use fieldkit::voxelize::Separation;
use glam::{Vec2, Vec3};

use super::scenes::{
    self, ActorDraw, ActorSettings, COLOUR, DEPTH, DistanceSettings, NAMES, OceanSettings, Saved,
    Scenes, VolumeSettings, VoxelMode, VoxelizerSettings,
};
use super::{Args, draw_frame, frame_time, load_settings, read_colour, save_png, save_settings};

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
        let sum = self.passes.0.iter().map(|p| p.1).sum::<f64>();
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
        let s = &mut self.saved;
        match NAMES[self.scene] {
            "actor" => actor_panel(ui, &mut s.actor),
            "ocean" => ocean_panel(ui, &mut s.ocean),
            "volume" => volume_panel(ui, &mut s.volume),
            "distance2d" => distance_panel(ui, &mut s.distance),
            "voxelizer" => voxelizer_panel(ui, &mut s.voxelizer),
            _ => {
                ui.label(
                    "The island is the actor scene's field and march: its settings are \
                     edited there. The sea and the cloud:",
                );
                ocean_panel(ui, &mut s.ocean);
                volume_panel(ui, &mut s.volume);
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
        ui.add(Slider::new(&mut c.fov, 0.2..=2.0).text("field of view"));
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
        // Time: fixed steps when taking a screenshot (so it matches the offscreen render),
        // else the clock.
        let time = if self.shot.is_some() {
            frame_time(self.drawn)
        } else {
            self.start.elapsed().as_secs_f32()
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

/// The side panel's layout. Pinned at the top, `pinned`: the scene, the file, the timings and
/// the messages, each in a slot of its own that keeps its height. Beneath, `settings` scroll;
/// their widgets' ids hang off the scroll area's own id and the scene's name, so nothing above
/// (an error appearing, a note) moves them or ends an edit.
pub fn side_panel(
    ui: &mut Ui,
    scene: &str,
    pinned: impl FnOnce(&mut Ui),
    settings: impl FnOnce(&mut Ui),
) {
    pinned(ui);
    ui.separator();
    egui::ScrollArea::vertical()
        .id_salt("scene settings")
        .show(ui, |ui| {
            ui.push_id(scene, settings);
        });
}

/// A drop-down named `label` of `options` (a value, its readable name) for `value`, the one
/// shown being the first option `same` holds equal to it (its name, else "other").
pub fn choice<T: Clone>(
    ui: &mut Ui,
    label: &str,
    value: &mut T,
    options: &[(T, &str)],
    same: impl Fn(&T, &T) -> bool,
) {
    let shown = options
        .iter()
        .find(|(o, _)| same(value, o))
        .map_or("other", |(_, name)| name);
    ComboBox::from_label(label)
        .selected_text(shown)
        .show_ui(ui, |ui| {
            for (option, name) in options {
                let selected = same(value, option);
                if ui.selectable_label(selected, *name).clicked() && !selected {
                    *value = option.clone();
                }
            }
        });
}

/// A slider whose value is taken when its drag ends (or a number typed into it is entered):
/// while it is dragged the knob moves and `value` stays, so a setting that costs a rebuild is
/// rebuilt once.
pub fn slider_on_release<N>(
    ui: &mut Ui,
    value: &mut N,
    range: std::ops::RangeInclusive<N>,
    text: &str,
) -> egui::Response
where
    N: egui::emath::Numeric + Send + Sync + 'static,
{
    let key = ui.scope_id().with(("dragged value", text));
    let mut v = ui.data(|d| d.get_temp::<N>(key)).unwrap_or(*value);
    let r = ui.add(
        Slider::new(&mut v, range)
            .text(text)
            .update_while_editing(false),
    );
    if r.dragged() {
        ui.data_mut(|d| d.insert_temp(key, v));
    } else {
        *value = v;
        ui.data_mut(|d| d.remove::<N>(key));
    }
    r
}

/// The scene drop-down: `scene` indexes [`NAMES`].
pub fn scene_row(ui: &mut Ui, scene: &mut usize) {
    ComboBox::from_label("scene")
        .selected_text(NAMES[*scene])
        .show_ui(ui, |ui| {
            for (i, n) in NAMES.iter().enumerate() {
                ui.selectable_value(scene, i, *n);
            }
        });
}

/// The settings file's path and its Save and Load buttons; `note` the outcome, and whether
/// it failed.
pub fn file_row(
    ui: &mut Ui,
    path: &mut String,
    saved: &mut Saved,
    note: &mut Option<(String, bool)>,
) {
    let id = ui.label("file").id;
    ui.add(egui::TextEdit::singleline(path).desired_width(120.0))
        .labelled_by(id);
    if ui.button("Save").clicked() {
        *note = Some(match save_settings(path.as_ref(), saved) {
            Ok(()) => (format!("saved {path}"), false),
            Err(e) => (e, true),
        });
    }
    if ui.button("Load").clicked() {
        match load_settings(path.as_ref()) {
            Ok(s) => {
                *saved = s;
                *note = Some((format!("loaded {path}"), false));
            }
            Err(e) => *note = Some((e, true)),
        }
    }
}

/// The settings after each finished change, for Undo: a change is taken in once it is over
/// (a drag released, a typed number entered), so one drag is one step.
pub struct History {
    committed: Saved,
    undo: Vec<Saved>,
}

impl History {
    /// Steps kept.
    const STEPS: usize = 64;

    pub fn new(saved: &Saved) -> Self {
        Self {
            committed: saved.clone(),
            undo: Vec::new(),
        }
    }

    /// Take in `now` where it differs from the last settled settings and no change is under
    /// way.
    pub fn settle(&mut self, now: &Saved, interacting: bool) {
        if !interacting && !same_settings(now, &self.committed) {
            let before = std::mem::replace(&mut self.committed, now.clone());
            self.undo.push(before);
            if self.undo.len() > Self::STEPS {
                self.undo.remove(0);
            }
        }
    }

    pub fn can_undo(&self) -> bool {
        !self.undo.is_empty()
    }

    /// The settings before the last change, which become the settled ones, with `now`'s
    /// cameras (a camera's moves are not steps).
    pub fn undo(&mut self, now: &Saved) -> Option<Saved> {
        let mut s = self.undo.pop()?;
        s.cameras.clone_from(&now.cameras);
        self.committed = s.clone();
        Some(s)
    }
}

/// Whether `a` and `b` hold the same settings, cameras aside.
fn same_settings(a: &Saved, b: &Saved) -> bool {
    a.actor == b.actor
        && a.ocean == b.ocean
        && a.volume == b.volume
        && a.distance == b.distance
        && a.voxelizer == b.voxelizer
}

/// Fold a frame's `passes` (read number `read`) into `seen`: a name's time is its passes'
/// sum in the latest frame that ran it.
pub fn remember(seen: &mut Vec<(String, f64, u64)>, passes: &[(String, f64)], read: u64) {
    for (name, ms) in passes {
        match seen.iter_mut().find(|s| s.0 == *name) {
            Some(s) if s.2 == read => s.1 += ms,
            Some(s) => *s = (name.clone(), *ms, read),
            None => seen.push((name.clone(), *ms, read)),
        }
    }
}

/// Lines of scene numbers the pinned panel keeps room for.
const STAT_LINES: usize = 4;

pub const ERROR_RED: egui::Color32 = egui::Color32::from_rgb(255, 110, 90);

/// `text` on one line of fixed height, cut short to the panel's width (the whole text on
/// hover); an empty line where there is none.
pub fn one_line(ui: &mut Ui, text: &str, colour: egui::Color32) {
    let label = egui::Label::new(egui::RichText::new(text).color(colour)).truncate();
    ui.add(label);
}

fn vec3_row(ui: &mut Ui, label: &str, v: &mut Vec3, speed: f32) {
    ui.horizontal(|ui| {
        ui.label(label);
        for (c, axis) in [(&mut v.x, "x"), (&mut v.y, "y"), (&mut v.z, "z")] {
            let id = ui.label(axis).id;
            ui.add(DragValue::new(c).speed(speed)).labelled_by(id);
        }
    });
}

pub fn actor_panel(ui: &mut Ui, s: &mut ActorSettings) {
    ui.heading("voxel actor (seed 000)");
    ui.horizontal(|ui| {
        ui.label("preset");
        if ui.button("fieldkit").clicked() {
            *s = ActorSettings::default();
        }
        if ui
            .button("seed")
            .on_hover_text("the source's settings: falloffExtend 1.5, full-volume JFA, its march, cubes and animation")
            .clicked()
        {
            *s = ActorSettings::seed();
        }
    });
    ui.horizontal(|ui| {
        ui.label("Extent");
        for (e, axis) in s.extent.iter_mut().zip(["x", "y", "z"]) {
            // Rebuilds the instances: taken on Enter, not per keystroke; not clamped, so too
            // large a value is the count's error below, not silently another value.
            let label = ui.label(axis).id;
            ui.add(
                DragValue::new(e)
                    .speed(0.1)
                    .range(0.0..=f32::MAX)
                    .update_while_editing(false),
            )
            .labelled_by(label);
        }
    });
    // Costly to apply: taken when the drag ends or the number typed is entered.
    slider_on_release(ui, &mut s.block, 0.1..=4.0, "BlockSize");
    match s.counts() {
        Ok(n) => ui.label(format!("{} × {} × {} blocks", n[0], n[1], n[2])),
        Err(e) => ui.colored_label(ERROR_RED, e.to_string()),
    };
    choice(
        ui,
        "draw",
        &mut s.draw,
        &[
            (ActorDraw::Surface, "surface (SDF march)"),
            (ActorDraw::Cubes, "debug cubes"),
            (ActorDraw::Both, "surface and cubes"),
            (
                ActorDraw::Direct(Direct::SphereGlobal),
                "direct: global Lipschitz bound",
            ),
            (
                ActorDraw::Direct(Direct::Segment),
                "direct: segment tracing",
            ),
        ],
        PartialEq::eq,
    );
    ComboBox::from_label("SDF method")
        .selected_text(s.field.method.name())
        .show_ui(ui, |ui| {
            use fieldkit::distance::{Method, Variant};
            for m in [
                Method::Lines,
                Method::Jfa(Variant::Jfa),
                Method::Jfa(Variant::JfaPlus1),
                Method::Jfa(Variant::JfaPlus2),
                Method::Jfa(Variant::OnePlusJfa),
            ] {
                ui.selectable_value(&mut s.field.method, m, m.name());
            }
        });
    choice(
        ui,
        "view",
        &mut s.raymarch.output,
        &[
            (MarchOutput::Shaded, "shaded"),
            (MarchOutput::Sdf, "distance at entry (red out, blue in)"),
            (MarchOutput::Density, "density"),
            (MarchOutput::Steps, "steps (heat: blue few, red the cap)"),
        ],
        PartialEq::eq,
    );
    ui.add(Slider::new(&mut s.field.threshold, 0.05..=0.95).text("threshold"));
    ui.add(Slider::new(&mut s.field.overlap, 1.0..=4.0).text("overlap"));
    ui.add(Slider::new(&mut s.field.cells_per_edge, 1.0..=8.0).text("cells per edge"));
    ui.add(Slider::new(&mut s.field.band, 2.0..=16.0).text("band (cells)"));
    ui.add(Slider::new(&mut s.raymarch.max_steps, 8..=512).text("max steps"));
    ui.add(Slider::new(&mut s.raymarch.safety, 0.3..=1.0).text("step safety"));
    ui.checkbox(&mut s.animate, "animate");
    ui.add(Slider::new(&mut s.animation.scale_frequency, 0.0..=3.0).text("scale frequency"));
    ui.add(Slider::new(&mut s.animation.scale_amplitude, 0.0..=1.0).text("scale amplitude"));
    ui.add(Slider::new(&mut s.animation.offset_frequency, 0.0..=3.0).text("offset frequency"));
    ui.add(Slider::new(&mut s.animation.offset_amplitude, 0.0..=0.5).text("offset amplitude"));
    ui.add(Slider::new(&mut s.animation.phase_step, 0.0..=1.0).text("phase step"));
    ui.checkbox(&mut s.field.full_volume, "full-volume field (JFA)");
    ui.add(Slider::new(&mut s.field.falloff_extend, 1.0..=2.0).text("falloff extend"));
    ui.collapsing("debug cubes", |ui| {
        choice(
            ui,
            "cull",
            &mut s.cubes.cull,
            &[
                (None, "none"),
                (Some(wgpu::Face::Back), "back faces"),
                (Some(wgpu::Face::Front), "front faces"),
            ],
            PartialEq::eq,
        );
        choice(
            ui,
            "depth test",
            &mut s.cubes.depth_compare,
            &[
                (wgpu::CompareFunction::Always, "always pass"),
                (wgpu::CompareFunction::Less, "nearer"),
                (wgpu::CompareFunction::LessEqual, "nearer or equal"),
            ],
            PartialEq::eq,
        );
        ui.checkbox(&mut s.cubes.wireframe, "wireframe");
        ui.checkbox(&mut s.cubes.depth_write, "depth write");
        ui.checkbox(&mut s.cubes.frustum_cull, "frustum cull");
        ui.checkbox(&mut s.cubes.scale_size, "cube size follows the scale");
    });
}

pub fn ocean_panel(ui: &mut Ui, s: &mut OceanSettings) {
    ui.heading("ocean (seed 001)");
    ui.horizontal(|ui| {
        ui.label("preset");
        if ui.button("fieldkit").clicked() {
            *s = OceanSettings::default();
        }
        if ui
            .button("seed")
            .on_hover_text("the source's sea: a 30 cm fade, depth read only, no skirts")
            .clicked()
        {
            *s = OceanSettings::seed();
        }
    });
    // One row a wave under a header whose labels name each column's fields (for the eye and
    // for the accessibility tree).
    let mut remove = None;
    egui::Grid::new("waves").num_columns(7).show(ui, |ui| {
        let header = ["dir x", "dir z", "amp (m)", "λ (m)", "speed (m/s)"].map(|h| ui.label(h).id);
        ui.end_row();
        for (i, w) in s.waves.iter_mut().enumerate() {
            // A wave the ocean refuses: the field its reason names framed in red, the reason
            // on the row.
            let why = w.check().err();
            let field = |name: &str| why.as_deref().is_some_and(|y| y.starts_with(name));
            let bad = [
                field("direction"),
                field("direction"),
                field("amplitude"),
                field("wavelength"),
                field("speed"),
            ];
            for ((value, speed, label), bad) in [
                (&mut w.direction.x, 0.02, header[0]),
                (&mut w.direction.y, 0.02, header[1]),
                (&mut w.amplitude, 0.01, header[2]),
                (&mut w.wavelength, 0.1, header[3]),
                (&mut w.speed, 0.05, header[4]),
            ]
            .into_iter()
            .zip(bad)
            {
                let r = ui
                    .add(DragValue::new(value).speed(speed))
                    .labelled_by(label);
                if bad {
                    let stroke = egui::Stroke::new(1.5, ERROR_RED);
                    ui.painter().rect_stroke(
                        r.rect.expand(1.0),
                        2.0,
                        stroke,
                        egui::StrokeKind::Outside,
                    );
                }
            }
            if ui
                .small_button("remove")
                .on_hover_text(format!("remove wave {i}"))
                .clicked()
            {
                remove = Some(i);
            }
            if let Some(why) = &why {
                ui.colored_label(ERROR_RED, why);
            }
            ui.end_row();
        }
    });
    if let Some(i) = remove {
        s.waves.remove(i);
    }
    if ui.button("add a wave").clicked() {
        s.waves.push(fieldkit::ocean::Wave {
            direction: glam::Vec2::new(0.5, 0.5),
            amplitude: 0.05,
            wavelength: 6.0,
            speed: 3.0,
        });
    }
    ui.add(Slider::new(&mut s.steepness, 0.0..=1.0).text("steepness"));
    ui.add(Slider::new(&mut s.lod.max_error_px, 0.25..=16.0).text("LOD error (px)"));
    ui.checkbox(&mut s.overlay, "draw the patch quadtree");
    ui.checkbox(&mut s.fade, "depth fade");
    ui.add(Slider::new(&mut s.look.fade_distance, 0.1..=20.0).text("fade distance (m)"));
    ui.add(Slider::new(&mut s.look.roughness, 0.0..=1.0).text("roughness"));
    ui.label(format!(
        "detail layers: {} height, {} normal",
        s.look.height_layers.len(),
        s.look.normal_layers.len()
    ));
    for (name, layers) in [
        ("height", &mut s.look.height_layers),
        ("normal", &mut s.look.normal_layers),
    ] {
        for (i, l) in layers.iter_mut().enumerate() {
            ui.horizontal(|ui| {
                let id = ui.label(format!("{name} {i}: tile (m)")).id;
                ui.add(DragValue::new(&mut l.tile).speed(0.1))
                    .labelled_by(id);
                let id = ui.label("strength").id;
                ui.add(DragValue::new(&mut l.strength).speed(0.01))
                    .labelled_by(id);
            });
        }
    }
    ComboBox::from_label("target")
        .selected_text(match s.gbuffer {
            None => "forward".to_string(),
            Some(i) => format!("G-buffer {i}"),
        })
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut s.gbuffer, None, "forward");
            for (i, n) in ["scene colour", "normal", "material", "base colour"]
                .iter()
                .enumerate()
            {
                ui.selectable_value(&mut s.gbuffer, Some(i), format!("G-buffer {i}: {n}"));
            }
        });
}

pub fn volume_panel(ui: &mut Ui, s: &mut VolumeSettings) {
    ui.heading("volume (seed 002)");
    ui.horizontal(|ui| {
        ui.checkbox(
            &mut s.function,
            "the cloud as a function, per sample (seed 0)",
        );
        if ui
            .button("seed")
            .on_hover_text("the source's cloud: the fBm evaluated per sample, shadow rays")
            .clicked()
        {
            *s = VolumeSettings::seed();
        }
    });
    // Costly to apply: taken when the drag ends or the number typed is entered.
    slider_on_release(ui, &mut s.size, 16..=256, "cloud voxels per side");
    ui.horizontal(|ui| {
        let id = ui.label("noise seed").id;
        ui.add(DragValue::new(&mut s.seed)).labelled_by(id);
    });
    ui.add(
        Slider::new(&mut s.march.step, 0.001..=0.05)
            .logarithmic(true)
            .text("step"),
    );
    // A kind's own numbers (the iso-level, the shadow step) stay as they are while its kind
    // is kept; choosing another kind takes the value listed here.
    let kind = |a: &_, b: &_| std::mem::discriminant(a) == std::mem::discriminant(b);
    choice(
        ui,
        "mode",
        &mut s.march.mode,
        &[
            (Mode::EmissionAbsorption, "emission-absorption"),
            (Mode::MaximumIntensity, "maximum intensity"),
            (Mode::IsoSurface { iso: 0.3 }, "iso-surface"),
        ],
        kind,
    );
    if let Mode::IsoSurface { iso } = &mut s.march.mode {
        ui.add(Slider::new(iso, 0.0..=1.0).text("iso-level (density)"));
    }
    choice(
        ui,
        "shadow",
        &mut s.march.shadow,
        &[
            (Shadow::None, "none"),
            (Shadow::Rays { step: 0.02 }, "rays to the light"),
            (Shadow::LightVolume { step: 0.02 }, "light volume"),
        ],
        |a, b| std::mem::discriminant(a) == std::mem::discriminant(b),
    );
    if let Shadow::Rays { step } | Shadow::LightVolume { step } = &mut s.march.shadow {
        ui.add(
            Slider::new(step, 0.002..=0.1)
                .logarithmic(true)
                .text("shadow step (volume units)"),
        );
    }
    ui.checkbox(&mut s.march.skip, "empty-space skipping");
    ui.checkbox(&mut s.march.jitter, "jitter");
    ui.add(Slider::new(&mut s.march.ambient, 0.0..=1.0).text("ambient"));
    vec3_row(ui, "light", &mut s.march.light_dir, 0.02);
    ui.horizontal(|ui| {
        ui.label("transfer function");
        if ui.button("cloud").clicked() {
            s.tf = TransferFunction::cloud();
        }
        if ui.button("white").clicked() {
            s.tf = TransferFunction::constant(Vec3::ONE, 0.05);
        }
    });
    ui.horizontal(|ui| {
        ui.label("density range");
        for (end, name) in s.tf.range.iter_mut().zip(["from", "to"]) {
            let id = ui.label(name).id;
            ui.add(DragValue::new(end).speed(0.01)).labelled_by(id);
        }
    });
}

pub fn distance_panel(ui: &mut Ui, s: &mut DistanceSettings) {
    ui.heading("2D distance (seed 003)");
    ui.label("left button: draw seeds, right: erase");
    ComboBox::from_label("method")
        .selected_text(scenes::method_name(s.options.method))
        .show_ui(ui, |ui| {
            for m in scenes::methods_2d() {
                ui.selectable_value(&mut s.options.method, m, scenes::method_name(m));
            }
        });
    ui.checkbox(&mut s.options.signed, "signed");
    use fieldkit::distance::Channels;
    choice(
        ui,
        "seed rule",
        &mut s.options.seeds.channels,
        &[
            (Channels::Red, "red channel"),
            (Channels::AnyColour, "any colour channel"),
            (Channels::Alpha, "alpha"),
        ],
        PartialEq::eq,
    );
    ui.add(Slider::new(&mut s.options.seeds.above, 0.0..=1.0).text("seed above"));
    ui.horizontal(|ui| {
        ui.label("preset");
        if ui.button("fieldkit").clicked() {
            s.options.seeds = fieldkit::distance::SeedRule::default();
        }
        if ui
            .button("seed")
            .on_hover_text("the source's rule: every non-black texel is a seed")
            .clicked()
        {
            s.options.seeds = fieldkit::distance::SeedRule::seed();
        }
    });
    ui.add(Slider::new(&mut s.brush, 0..=12).text("brush radius"));
    ui.add(Slider::new(&mut s.iso_period, 1.0..=32.0).text("iso-line period"));
    ui.horizontal(|ui| {
        ui.label("size");
        for (side, axis) in s.size.iter_mut().zip(["w", "h"]) {
            let id = ui.label(axis).id;
            ui.add(
                DragValue::new(side)
                    .range(1..=4096)
                    .update_while_editing(false),
            )
            .labelled_by(id);
        }
    });
    ui.horizontal(|ui| {
        if ui.button("clear seeds").clicked() {
            s.seeds.clear();
        }
        if ui.button("default seeds").clicked() {
            s.seeds = DistanceSettings::default().seeds;
        }
    });
}

pub fn voxelizer_panel(ui: &mut Ui, s: &mut VoxelizerSettings) {
    ui.heading("voxelizer (seed 004)");
    ui.checkbox(&mut s.point_light, "point light (the source's demo scene)");
    ui.horizontal(|ui| {
        let id = ui.label("mesh").id;
        ui.text_edit_singleline(&mut s.mesh).labelled_by(id);
    });
    ui.horizontal(|ui| {
        for m in ["torus", "sphere", scenes::BUNNY] {
            if ui.small_button(m.rsplit('/').next().unwrap_or(m)).clicked() {
                s.mesh = m.into();
            }
        }
    });
    // Costly to apply: taken when the drag ends or the number typed is entered.
    slider_on_release(ui, &mut s.grid, 4..=512, "grid (longest side)");
    ui.add(
        Slider::new(&mut s.spin, -std::f32::consts::PI..=std::f32::consts::PI)
            .text("spin (about y)"),
    );
    choice(
        ui,
        "voxelization",
        &mut s.mode,
        &[
            (
                VoxelMode::Surface(Separation::Conservative),
                "surface, conservative (26-separating)",
            ),
            (VoxelMode::Surface(Separation::Six), "surface, 6-separating"),
            (VoxelMode::Raster, "surface through the rasterizer"),
            (VoxelMode::Solid, "solid (parity along x)"),
            (
                VoxelMode::DistanceField,
                "signed distance field, raymarched",
            ),
        ],
        PartialEq::eq,
    );
    choice(
        ui,
        "colour by",
        &mut s.colour_by,
        &[(ColourBy::Normal, "normal"), (ColourBy::Colour, "colour")],
        PartialEq::eq,
    );
    ui.checkbox(&mut s.slice, "signed distance slice (middle z)");
    ui.add(Slider::new(&mut s.band, 0.5..=16.0).text("distance band (voxels)"));
}
