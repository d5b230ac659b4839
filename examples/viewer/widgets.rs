//! The viewer's own widgets and the state behind them: the side panel's layout, drop-downs with
//! readable names, sliders that apply on release, one-line message slots, the scene and file
//! rows, Undo's history and the per-pass list.

use eframe::egui;
use egui::{ComboBox, DragValue, Slider, Ui};
use glam::Vec3;

use super::scenes::{Legend, NAMES, Saved};
use super::{load_settings, save_settings};

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
/// rebuilt once. A typed number outside the rail is kept as typed.
pub fn slider_on_release<N>(
    ui: &mut Ui,
    value: &mut N,
    range: std::ops::RangeInclusive<N>,
    text: &str,
    bad: bool,
) -> egui::Response
where
    N: egui::emath::Numeric + Send + Sync + 'static,
{
    let key = ui.scope_id().with(("dragged value", text));
    let mut v = ui.data(|d| d.get_temp::<N>(key)).unwrap_or(*value);
    // A number typed past the rail is taken as typed (and refused with the scene's own
    // error where it is wrong), never quietly changed into another.
    let shown = if bad {
        egui::RichText::new(format!("{text}{REFUSED}")).color(ERROR_RED)
    } else {
        egui::RichText::new(text)
    };
    let r = ui.add(
        Slider::new(&mut v, range)
            .text(shown)
            .update_while_editing(false)
            .clamping(egui::SliderClamping::Never),
    );
    mark(ui, &r, bad);
    if r.dragged() {
        ui.data_mut(|d| d.insert_temp(key, v));
    } else {
        *value = v;
        ui.data_mut(|d| d.remove::<N>(key));
    }
    r
}

/// A scene's presets: fieldkit's `default` and the source's `seed` (`hover` says what the seed
/// changes), each replacing `value` when clicked.
pub fn preset_row<T>(ui: &mut Ui, value: &mut T, default: T, seed: T, hover: &str) {
    ui.horizontal(|ui| {
        ui.label("preset");
        if ui.button("fieldkit").clicked() {
            *value = default;
        }
        if ui.button("seed").on_hover_text(hover).clicked() {
            *value = seed;
        }
    });
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

/// The GPU time of each group of passes (a pass named `group / pass`; see
/// `Profiler::group`) in the latest frame of `seen` that had any, in the order the groups
/// first appear.
pub fn group_totals(seen: &[(String, f64, u64)]) -> Vec<(String, f64)> {
    let grouped = |name: &str| name.split_once(" / ").map(|(g, _)| g.to_string());
    let latest = seen
        .iter()
        .filter(|s| grouped(&s.0).is_some())
        .map(|s| s.2)
        .max();
    let mut totals: Vec<(String, f64)> = Vec::new();
    for (name, ms, read) in seen {
        let Some(group) = grouped(name).filter(|_| Some(*read) == latest) else {
            continue;
        };
        match totals.iter_mut().find(|(g, _)| *g == group) {
            Some((_, sum)) => *sum += ms,
            None => totals.push((group, *ms)),
        }
    }
    totals
}

pub const ERROR_RED: egui::Color32 = egui::Color32::from_rgb(255, 110, 90);

/// What a control's label says after it while the scene's error comes from it.
pub const REFUSED: &str = " (refused)";

/// Frame `r`'s widget in red when `bad`: the control the scene's error came from.
pub fn mark(ui: &Ui, r: &egui::Response, bad: bool) {
    if bad {
        let stroke = egui::Stroke::new(1.5, ERROR_RED);
        ui.painter()
            .rect_stroke(r.rect.expand(1.0), 2.0, stroke, egui::StrokeKind::Outside);
    }
}

/// A control's label: red and followed by [`REFUSED`] when `bad`.
pub fn control_label(ui: &mut Ui, text: &str, bad: bool) -> egui::Response {
    if bad {
        ui.colored_label(ERROR_RED, format!("{text}{REFUSED}"))
    } else {
        ui.label(text)
    }
}

/// `text` on one line of fixed height, cut short to the panel's width (the whole text on
/// hover); an empty line where there is none.
pub fn one_line(ui: &mut Ui, text: &str, colour: egui::Color32) {
    let label = egui::Label::new(egui::RichText::new(text).color(colour)).truncate();
    ui.add(label);
}

pub fn vec3_row(ui: &mut Ui, label: &str, v: &mut Vec3, speed: f32) {
    ui.horizontal(|ui| {
        ui.label(label);
        for (c, axis) in [(&mut v.x, "x"), (&mut v.y, "y"), (&mut v.z, "z")] {
            let id = ui.label(axis).id;
            ui.add(DragValue::new(c).speed(speed)).labelled_by(id);
        }
    });
}

/// The legends of the debug views shown, in the lower-left corner of `rect` (the view), each
/// a title, its ramp between the values at its ends, and its single colours with what each
/// means. The texts are labels, so the accessibility tree (and the tests) read them.
pub fn draw_legends(ctx: &egui::Context, rect: egui::Rect, legends: &[Legend]) {
    if legends.is_empty() {
        return;
    }
    egui::Area::new(egui::Id::unique("debug view legends"))
        .order(egui::Order::Foreground)
        .pivot(egui::Align2::LEFT_BOTTOM)
        .fixed_pos(rect.left_bottom() + egui::vec2(8.0, -8.0))
        .interactable(false)
        .show(ctx, |ui| {
            egui::Frame::new()
                .fill(egui::Color32::from_black_alpha(190))
                .inner_margin(6.0)
                .corner_radius(4.0)
                .show(ui, |ui| {
                    for legend in legends {
                        legend_block(ui, legend);
                    }
                });
        });
}

fn legend_block(ui: &mut Ui, legend: &Legend) {
    let rgb = |c: [u8; 3]| egui::Color32::from_rgb(c[0], c[1], c[2]);
    ui.label(egui::RichText::new(&legend.title).strong());
    if !legend.ramp.is_empty() {
        ui.horizontal(|ui| {
            ui.label(&legend.ends[0]);
            let (r, _) = ui.allocate_exact_size(egui::vec2(120.0, 12.0), egui::Sense::hover());
            let w = r.width() / legend.ramp.len() as f32;
            for (i, c) in legend.ramp.iter().enumerate() {
                let x = r.left() + i as f32 * w;
                let cell = egui::Rect::from_min_max(
                    egui::pos2(x, r.top()),
                    egui::pos2(x + w + 0.5, r.bottom()),
                );
                ui.painter().rect_filled(cell, 0.0, rgb(*c));
            }
            ui.label(&legend.ends[1]);
        });
    }
    for (c, what) in &legend.keys {
        ui.horizontal(|ui| {
            let (r, _) = ui.allocate_exact_size(egui::vec2(12.0, 12.0), egui::Sense::hover());
            ui.painter().rect_filled(r, 2.0, rgb(*c));
            ui.label(what);
        });
    }
}
