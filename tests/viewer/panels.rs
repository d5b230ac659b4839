//! The viewer's panels driven as a user drives them, through egui's test harness (egui_kittest:
//! pointer and keyboard events, the accessibility tree read back), without a window or a GPU:
//! a number typed while an error shows keeps every keystroke, an expensive field takes what is
//! typed on Enter and not per keystroke, and "Defaults" resets one scene.

use crate::viewer;

use eframe::egui;
use egui::accesskit::Role;
use egui_kittest::Harness;
use egui_kittest::kittest::Queryable;
use viewer::scene_panels::{actor_panel, ocean_panel};
use viewer::scenes::{ActorSettings, OceanSettings, Saved};
use viewer::widgets::{ERROR_RED, one_line, side_panel};

/// The ocean panel beneath a pinned error line, laid out as the viewer lays out its side
/// panel: the error ("wave 0 wavelength …") shows while the first wave's wavelength is not
/// positive.
fn ocean_with_error(ui: &mut egui::Ui, s: &mut OceanSettings) {
    let wavelength = s.waves[0].wavelength;
    let error = (wavelength <= 0.0).then(|| format!("wave 0 wavelength {wavelength} must be > 0"));
    side_panel(
        ui,
        "ocean",
        |ui| one_line(ui, error.as_deref().unwrap_or(""), ERROR_RED),
        |ui| ocean_panel(ui, s, None),
    );
}

/// The actor's panel on its default settings, laid out once.
fn actor_harness() -> Harness<'static, ActorSettings> {
    let mut harness = Harness::new_ui_state(
        |ui, s: &mut ActorSettings| actor_panel(ui, s, None),
        ActorSettings::default(),
    );
    harness.run();
    harness
}

/// Type `text` into the `index`-th number field (a click enters its text edit), then Enter.
fn type_into<S>(harness: &mut Harness<'_, S>, index: usize, text: &str) {
    harness
        .get_all_by_role(Role::SpinButton)
        .nth(index)
        .expect("a number field")
        .click();
    harness.run();
    for c in text.chars() {
        harness.event(egui::Event::Text(c.to_string()));
        harness.run();
    }
    harness.key_press(egui::Key::Enter);
    harness.run();
}

#[test]
fn a_number_typed_while_an_error_shows_keeps_every_keystroke() {
    let mut s = OceanSettings::default();
    s.waves[0].wavelength = 0.0;
    let mut harness = Harness::new_ui_state(ocean_with_error, s);
    harness.run();
    assert!(
        harness.query_by_label_contains("must be > 0").is_some(),
        "the error shows"
    );
    // Direction x, z, amplitude, wavelength, speed: the wavelength is the fourth field. The
    // error goes with the first digit; the second must still land in the same field.
    type_into(&mut harness, 3, "21");
    assert_eq!(harness.state().waves[0].wavelength, 21.0);
    assert!(
        harness.query_by_label_contains("must be > 0").is_none(),
        "the error went"
    );
}

#[test]
fn an_expensive_field_takes_what_is_typed_on_enter() {
    let mut harness = actor_harness();
    let before = harness.state().extent[0];
    harness
        .get_all_by_role(Role::SpinButton)
        .next()
        .expect("Extent x")
        .click();
    harness.run();
    for c in ['0', '.', '5'] {
        harness.event(egui::Event::Text(c.to_string()));
        harness.run();
        // Not one keystroke rebuilds the blocks (a lone "0" would have made zero of them).
        assert_eq!(harness.state().extent[0], before, "applied at {c:?}");
    }
    harness.key_press(egui::Key::Enter);
    harness.run();
    assert_eq!(harness.state().extent[0], 0.5);
}

#[test]
fn defaults_reset_one_scene_and_keep_the_mesh() {
    let mut s = Saved::default();
    s.ocean.steepness = 0.123;
    s.actor.block = 2.5;
    s.voxelizer.mesh = "my/mesh.obj".into();
    s.voxelizer.grid = 200;
    s.reset_scene("voxelizer");
    assert_eq!(s.voxelizer.grid, Saved::default().voxelizer.grid);
    assert_eq!(s.voxelizer.mesh, "my/mesh.obj", "the mesh chosen stays");
    assert_eq!(
        (s.ocean.steepness, s.actor.block),
        (0.123, 2.5),
        "the other scenes stay"
    );
    s.reset_scene("ocean");
    assert_eq!(s.ocean, Saved::default().ocean);
    assert_eq!(s.actor.block, 2.5);
}

/// Drop-downs show readable names, never a Rust debug name: the voxelizer's, the volume's (a
/// kind's own number shown beside it) and the actor's.
#[test]
fn choices_have_readable_names() {
    use viewer::scene_panels::{volume_panel, voxelizer_panel};
    use viewer::scenes::{VolumeSettings, VoxelizerSettings};
    let mut harness = Harness::new_ui_state(
        |ui, s: &mut (VoxelizerSettings, VolumeSettings, ActorSettings)| {
            voxelizer_panel(ui, &mut s.0, None);
            volume_panel(ui, &mut s.1, None);
            actor_panel(ui, &mut s.2, None);
        },
        Default::default(),
    );
    harness.run();
    // What each drop-down shows is its value in the accessibility tree.
    for shown in [
        "surface, conservative (26-separating)",
        "emission-absorption",
        "light volume",
        "surface (SDF march)",
    ] {
        assert!(
            harness.query_by_value(shown).is_some(),
            "{shown:?} is not shown"
        );
    }
    for debug in [
        "Surface(",
        "Direct(",
        "LightVolume {",
        "Rays {",
        "Conservative)",
    ] {
        assert!(
            harness.query_by_label_contains(debug).is_none(),
            "a debug name shows: {debug}"
        );
    }
}

/// The per-pass list keeps a pass that ran in an earlier frame (the 2D tool's methods run only
/// when the seeds change) with the time it took there, and sums a name's passes in one frame.
#[test]
fn passes_stay_listed_with_their_last_time() {
    use viewer::widgets::remember;
    let mut seen = Vec::new();
    let frame = |p: &[(&str, f64)]| {
        p.iter()
            .map(|(n, ms)| (n.to_string(), *ms))
            .collect::<Vec<_>>()
    };
    remember(
        &mut seen,
        &frame(&[("exact", 0.25), ("jfa", 0.5), ("jfa", 0.25), ("blit", 0.01)]),
        1,
    );
    remember(&mut seen, &frame(&[("blit", 0.02)]), 2);
    assert_eq!(
        seen,
        vec![
            ("exact".to_string(), 0.25, 1),
            ("jfa".to_string(), 0.75, 1),
            ("blit".to_string(), 0.02, 2),
        ]
    );
}

/// A drag in the 2D tool paints a stroke: every texel on the line between two frames' pointer
/// positions, not two separate stamps.
#[test]
fn a_drag_paints_a_stroke() {
    use viewer::scenes::{DistanceSettings, line};
    assert_eq!(line([0, 0], [3, 1]), vec![[0, 0], [1, 0], [2, 1], [3, 1]]);
    assert_eq!(line([5, 9], [5, 6]), vec![[5, 9], [5, 8], [5, 7], [5, 6]]);
    assert_eq!(line([2, 2], [2, 2]), vec![[2, 2]]);
    let mut d = DistanceSettings {
        brush: 0,
        ..DistanceSettings::default()
    };
    d.seeds.clear();
    d.paint_stroke([10, 10], [20, 10], false);
    assert_eq!(d.seeds.len(), 11, "{:?}", d.seeds);
    d.paint_stroke([12, 10], [14, 10], true);
    assert_eq!(d.seeds.len(), 8, "erased along its own stroke");
}

/// Undo takes back the last finished change, not each frame of a drag, and leaves the camera
/// where it is.
#[test]
fn undo_takes_back_the_last_finished_change() {
    use viewer::widgets::History;
    let start = Saved::default();
    let mut history = History::new(&start);
    let mut now = start.clone();
    // A drag of the steepness over three frames, then released.
    for k in 1..=3 {
        now.ocean.steepness = 0.1 * k as f32;
        history.settle(&now, true);
    }
    history.settle(&now, false);
    // A camera move alone is no step.
    now.cameras[0].distance += 5.0;
    history.settle(&now, false);
    now.actor.block = 3.0;
    history.settle(&now, false);
    let back = history.undo(&now).expect("a step");
    assert_eq!(
        (back.actor.block, back.ocean.steepness),
        (start.actor.block, 0.3)
    );
    assert_eq!(
        back.cameras[0].distance, now.cameras[0].distance,
        "the camera stays"
    );
    let back = history.undo(&back).expect("the drag, one step");
    assert_eq!(back.ocean.steepness, start.ocean.steepness);
    assert!(history.undo(&back).is_none(), "{} steps", 2);
}

/// An Extent too large for the actor is said so in red beside it, not clamped to another value.
#[test]
fn a_value_too_large_is_said_not_clamped() {
    let mut harness = actor_harness();
    type_into(&mut harness, 0, "99999");
    assert_eq!(harness.state().extent[0], 99999.0, "taken as typed");
    assert!(
        harness.query_by_label_contains("instances").is_some(),
        "the count's error names the instances"
    );
}

/// Save writes the settings where the path says, Load brings them back, a file that is not
/// there is a note in red (failed), and the scene drop-down switches the scene.
#[test]
fn save_load_round_trip_and_scene_switch() {
    use viewer::widgets::{file_row, scene_row};
    let path = std::env::temp_dir().join(format!("fieldkit_viewer_ui_{}.ron", std::process::id()));
    struct State {
        path: String,
        saved: Saved,
        note: Option<(String, bool)>,
        scene: usize,
    }
    let state = State {
        path: path.display().to_string(),
        saved: Saved::default(),
        note: None,
        scene: 0,
    };
    let mut harness = Harness::new_ui_state(
        |ui, s: &mut State| {
            scene_row(ui, &mut s.scene);
            ui.horizontal(|ui| file_row(ui, &mut s.path, &mut s.saved, &mut s.note));
        },
        state,
    );
    harness.state_mut().saved.ocean.steepness = 0.42;
    harness.run();
    harness.get_by_label("Save").click();
    harness.run();
    assert!(path.exists(), "{:?}", harness.state().note);
    assert_eq!(harness.state().note.as_ref().map(|n| n.1), Some(false));
    harness.state_mut().saved.ocean.steepness = 0.9;
    harness.get_by_label("Load").click();
    harness.run();
    assert_eq!(harness.state().saved.ocean.steepness, 0.42, "loaded back");
    std::fs::remove_file(&path).ok();
    harness.get_by_label("Load").click();
    harness.run();
    let note = harness.state().note.clone().expect("a note");
    assert!(note.1, "a missing file is a failure: {note:?}");
    assert_eq!(
        harness.state().saved.ocean.steepness,
        0.42,
        "nothing loaded"
    );
    // The scene drop-down: open it, pick the ocean.
    harness.get_by_value("actor").click();
    harness.run();
    harness.get_by_label("ocean").click();
    harness.run();
    assert_eq!(viewer::scenes::NAMES[harness.state().scene], "ocean");
}

/// A costly slider (the actor's BlockSize) moves its knob while dragged and takes the value
/// when the drag ends: one rebuild, not one a frame.
#[test]
fn a_costly_slider_applies_on_release() {
    let mut harness = actor_harness();
    let before = harness.state().block;
    let rect = harness
        .get_by_role_and_label(Role::Slider, "BlockSize (units)")
        .rect();
    let (y, from, to) = (
        rect.center().y,
        rect.left() + 4.0,
        rect.left() + rect.width() * 0.8,
    );
    let button = |pos: egui::Pos2, pressed| egui::Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: egui::Modifiers::NONE,
    };
    harness.event(egui::Event::PointerMoved(egui::pos2(from, y)));
    harness.event(button(egui::pos2(from, y), true));
    harness.run();
    for k in 1..=4 {
        let x = from + (to - from) * k as f32 / 4.0;
        harness.event(egui::Event::PointerMoved(egui::pos2(x, y)));
        harness.run();
        assert_eq!(
            harness.state().block,
            before,
            "applied while dragging, step {k}"
        );
    }
    harness.event(button(egui::pos2(to, y), false));
    harness.run();
    let after = harness.state().block;
    assert!(
        after > before + 1.0,
        "taken on release: {before} -> {after}"
    );
}

/// A number typed into a costly slider past its rail is taken as typed and refused by the
/// scene's own check (BlockSize 0: the blocks' count says why in red), not clamped into range.
#[test]
fn a_number_typed_past_a_slider_is_kept_and_refused() {
    let mut harness = actor_harness();
    // The slider's number is the spin button after Extent's three.
    type_into(&mut harness, 3, "0");
    assert_eq!(harness.state().block, 0.0, "taken as typed");
    assert!(
        harness
            .query_by_label_contains("BlockSize must be finite and > 0")
            .is_some()
    );
}

/// The control a scene's error came from is found from the settings (each scene's own checks
/// run again), and its panel marks it: red, its label followed by "(refused)".
#[test]
fn a_refused_setting_marks_its_control() {
    use viewer::scenes::{Control, Scenes};
    let scenes = Scenes::new();
    let culprit = |scene: &str, change: &dyn Fn(&mut Saved)| {
        let mut s = Saved::default();
        s.voxelizer.mesh = "torus".into();
        change(&mut s);
        scenes.culprit(scene, &s)
    };
    assert_eq!(culprit("actor", &|_| ()), None, "nothing refused");
    assert_eq!(
        culprit("actor", &|s| s.actor.extent = [99999.0; 3]),
        Some(Control::Extent)
    );
    assert_eq!(
        culprit("actor", &|s| s.actor.block = 0.0),
        Some(Control::BlockSize)
    );
    assert_eq!(
        culprit("distance2d", &|s| s.distance.size = [0, 40]),
        Some(Control::MaskSize)
    );
    assert_eq!(
        culprit("volume", &|s| s.volume.size = 3),
        Some(Control::CloudSize)
    );
    assert_eq!(
        culprit("ocean", &|s| s.ocean.waves[1].amplitude = f32::NAN),
        Some(Control::Wave(1))
    );
    assert_eq!(
        culprit("composite", &|s| s.ocean.look.height_layers[0].tile = 0.0),
        Some(Control::HeightLayer(0)),
        "the composite edits the sea"
    );
    assert_eq!(
        culprit("voxelizer", &|s| s.voxelizer.spin = f32::INFINITY),
        Some(Control::Spin)
    );
    // No mesh loaded under the name asked for: the one it could not load.
    assert_eq!(
        culprit("voxelizer", &|s| s.voxelizer.mesh = "no/such.obj".into()),
        Some(Control::Mesh)
    );

    let mut harness = Harness::new_ui_state(
        |ui, s: &mut (ActorSettings, Option<Control>)| actor_panel(ui, &mut s.0, s.1),
        (ActorSettings::default(), None),
    );
    harness.run();
    assert!(
        harness
            .query_all_by_label_contains("(refused)")
            .next()
            .is_none()
    );
    harness.state_mut().1 = Some(Control::Extent);
    harness.run();
    assert!(
        harness
            .query_all_by_label_contains("Extent (units) (refused)")
            .next()
            .is_some()
    );
    harness.state_mut().1 = Some(Control::BlockSize);
    harness.run();
    assert!(
        harness
            .query_all_by_label_contains("BlockSize (units) (refused)")
            .next()
            .is_some()
    );
    assert!(
        harness
            .query_by_label_contains("Extent (units) (refused)")
            .is_none()
    );
}

/// Every debug view has a legend and a lit picture has none; the legend is drawn, its texts
/// readable.
#[test]
fn every_debug_view_has_a_legend() {
    use fieldkit::metaball::Output;
    use viewer::widgets::draw_legends;
    let mut s = Saved::default();
    assert!(s.legends("actor").is_empty(), "the lit surface");
    for (output, title) in [
        (Output::Steps, "steps per ray"),
        (Output::Density, "density just inside the surface"),
        (Output::Sdf, "signed distance where the ray enters the box"),
    ] {
        s.actor.raymarch.output = output;
        let legends = s.legends("actor");
        assert_eq!(legends.len(), 1, "{output:?}");
        assert_eq!(legends[0].title, title);
        assert_eq!(legends[0].ramp.len(), viewer::scenes::RAMP_SAMPLES);
    }
    for i in 0..4 {
        s.ocean.gbuffer = Some(i);
        assert!(
            s.legends("ocean")[0]
                .title
                .starts_with(&format!("G-buffer {i}"))
        );
    }
    s.ocean.gbuffer = None;
    assert!(s.legends("ocean").is_empty(), "the lit sea");
    s.ocean.overlay = true;
    assert_eq!(s.legends("ocean").len(), 1, "the patch outlines");
    let d = &s.legends("distance2d")[0];
    assert!(d.keys.iter().any(|k| k.0 == [255, 0, 255]), "wrong texels");
    s.voxelizer.slice = true;
    assert!(
        s.legends("voxelizer")
            .iter()
            .any(|l| l.title.starts_with("signed distance"))
    );

    s.actor.raymarch.output = Output::Steps;
    let legends = s.legends("actor");
    let mut harness = Harness::new_ui(|ui| {
        draw_legends(
            ui.ctx(),
            egui::Rect::from_min_size(egui::Pos2::ZERO, egui::vec2(400.0, 300.0)),
            &legends,
        )
    });
    harness.run();
    for text in ["steps per ray", "0"] {
        assert!(harness.query_by_label(text).is_some(), "{text}");
    }
    assert!(harness.query_by_label_contains("the cap").is_some());
}

/// The 2D tool's passes, grouped by method, add up per method, from the latest frame that ran
/// them (the field is computed when the settings change, not every frame).
#[test]
fn passes_add_up_by_method() {
    use viewer::widgets::group_totals;
    let seen = vec![
        ("JFA / seed".to_string(), 0.5, 3),
        ("JFA / jump".to_string(), 1.0, 3),
        ("exact (reference) / rows".to_string(), 0.25, 3),
        ("exact (reference) / columns".to_string(), 0.5, 3),
        ("JFA+1 / jump".to_string(), 9.0, 2),
        ("blit".to_string(), 0.1, 4),
    ];
    assert_eq!(
        group_totals(&seen),
        vec![
            ("JFA".to_string(), 1.5),
            ("exact (reference)".to_string(), 0.75)
        ]
    );
    assert!(group_totals(&seen[5..]).is_empty());
}
