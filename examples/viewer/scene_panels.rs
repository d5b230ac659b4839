//! Each scene's settings panel, beneath the viewer's pinned top.

use eframe::egui;
use egui::{ComboBox, DragValue, Slider, Ui};
use fieldkit::metaball::{Direct, ExactSurface, Output as MarchOutput};
use fieldkit::volume::{Mode, Shadow, TransferFunction};
use fieldkit::voxelize::ColourBy;
use fieldkit::voxelize::Separation;
use glam::Vec3;

use super::scenes::Control;
use super::scenes::{
    self, ActorDraw, ActorSettings, DistanceSettings, OceanSettings, VolumeSettings, VoxelMode,
    VoxelizerSettings,
};
use super::widgets::{
    ERROR_RED, choice, control_label, mark, preset_row, slider_on_release, vec3_row,
};

pub fn actor_panel(ui: &mut Ui, s: &mut ActorSettings, bad: Option<Control>) {
    ui.heading("voxel actor (seed 000)");
    preset_row(
        ui,
        s,
        ActorSettings::default(),
        ActorSettings::seed(),
        "the source's settings: falloffExtend 1.5, full-volume JFA, its march, cubes and animation",
    );
    ui.horizontal(|ui| {
        let extent_bad = bad == Some(Control::Extent);
        control_label(ui, "Extent (units)", extent_bad).on_hover_text(
            "the region the blocks fill, per axis, in the source's units; blocks per axis = \
             max(1, ⌊Extent / BlockSize⌋)",
        );
        for (e, axis) in s.extent.iter_mut().zip(["x", "y", "z"]) {
            // Rebuilds the instances: taken on Enter, not per keystroke; not clamped, so too
            // large a value is the count's error below, not silently another value.
            let label = ui.label(axis).id;
            let r = ui
                .add(
                    DragValue::new(e)
                        .speed(0.1)
                        .range(0.0..=f32::MAX)
                        .update_while_editing(false),
                )
                .labelled_by(label);
            mark(ui, &r, extent_bad);
        }
    });
    // Costly to apply: taken when the drag ends or the number typed is entered.
    slider_on_release(
        ui,
        &mut s.block,
        0.1..=4.0,
        "BlockSize (units)",
        bad == Some(Control::BlockSize),
    )
    .on_hover_text("the edge of one block (one metaball), in Extent's units");
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
            (MarchOutput::Sdf, "distance where the ray enters the box"),
            (MarchOutput::Density, "density just inside the surface"),
            (MarchOutput::Steps, "steps per ray"),
        ],
        PartialEq::eq,
    );
    field_and_march_rows(ui, s);
    cubes_rows(ui, s);
}

/// The actor's field, march and animation numbers.
fn field_and_march_rows(ui: &mut Ui, s: &mut ActorSettings) {
    ui.add(Slider::new(&mut s.field.threshold, 0.05..=0.95).text("threshold (density)"))
        .on_hover_text("the iso-level of the surface: the summed (1 − d²/R²)³ falloffs");
    ui.add(Slider::new(&mut s.field.overlap, 1.0..=4.0).text("overlap (× half a block)"))
        .on_hover_text("a blob's support radius = block × scale × ½ × overlap × falloff extend");
    ui.add(Slider::new(&mut s.field.cells_per_edge, 1.0..=8.0).text("grid cells per block"))
        .on_hover_text("the SDF texture's resolution: cells per block edge");
    ui.add(Slider::new(&mut s.field.band, 2.0..=16.0).text("band (cells)"))
        .on_hover_text("distances the SDF holds exactly; clamped to ± this beyond");
    ui.add(Slider::new(&mut s.raymarch.max_steps, 8..=512).text("max steps per ray"))
        .on_hover_text("a ray that uses them all is marked, never a silent miss");
    ui.add(Slider::new(&mut s.raymarch.safety, 0.3..=1.0).text("step (× distance)"))
        .on_hover_text("each step is this fraction of the distance the SDF gives");
    ui.checkbox(&mut s.animate, "animate");
    ui.add(Slider::new(&mut s.animation.scale_frequency, 0.0..=3.0).text("scale pulses (per s)"));
    ui.add(Slider::new(&mut s.animation.scale_amplitude, 0.0..=1.0).text("scale pulse (fraction)"))
        .on_hover_text("0: none; 0.5: between 0 and the full scale");
    ui.add(Slider::new(&mut s.animation.offset_frequency, 0.0..=3.0).text("offset cycles (per s)"));
    ui.add(Slider::new(&mut s.animation.offset_amplitude, 0.0..=0.5).text("offset (block edges)"))
        .on_hover_text("the largest move of a blob's centre");
    ui.add(Slider::new(&mut s.animation.phase_step, 0.0..=1.0).text("phase step (rad)"))
        .on_hover_text("the phase between one block and the next");
    let mut exact = s.field.exact_surface != ExactSurface::Off;
    let when = s.field.exact_surface;
    if ui
        .checkbox(&mut exact, "exact surface (blobs near it)")
        .on_hover_text(format!(
            "within two cells of the surface the march steps on the blobs' own field, so no \
             grazing hit is lost to the texture's trilinear density (now: {when:?})"
        ))
        .changed()
    {
        s.field.exact_surface = if exact {
            ExactSurface::On
        } else {
            ExactSurface::Off
        };
    }
    ui.checkbox(&mut s.field.full_volume, "full-volume field (JFA)")
        .on_hover_text("a field over the whole box, not only the band the march needs");
    ui.add(Slider::new(&mut s.field.falloff_extend, 1.0..=2.0).text("falloff extend (×)"))
        .on_hover_text("a further factor on the support radius (the source: 1.5)");
}

/// The actor's debug cubes.
fn cubes_rows(ui: &mut Ui, s: &mut ActorSettings) {
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

pub fn ocean_panel(ui: &mut Ui, s: &mut OceanSettings, bad: Option<Control>) {
    ui.heading("ocean (seed 001)");
    preset_row(
        ui,
        s,
        OceanSettings::default(),
        OceanSettings::seed(),
        "the source's sea: a 30 cm fade, depth read only, no skirts",
    );
    waves_table(ui, &mut s.waves);
    ui.add(Slider::new(&mut s.steepness, 0.0..=1.0).text("steepness (Gerstner Q)"))
        .on_hover_text("0: sine waves; 1: crests just short of looping");
    ui.add(Slider::new(&mut s.lod.max_error_px, 0.25..=16.0).text("LOD error (px)"))
        .on_hover_text("the largest height error on screen the patch quadtree allows");
    ui.checkbox(&mut s.overlay, "draw the patch quadtree")
        .on_hover_text("each patch's outline over the water");
    ui.checkbox(&mut s.fade, "depth fade")
        .on_hover_text("shallow colour where the water is near the scene behind it");
    ui.add(Slider::new(&mut s.look.fade_distance, 0.1..=20.0).text("fade distance (m)"));
    ui.add(Slider::new(&mut s.look.roughness, 0.0..=1.0).text("roughness (0–1)"))
        .on_hover_text("the sun's highlight: 0 a point, 1 spread over the water");
    detail_layer_rows(ui, &mut s.look, bad);
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

/// The ocean's waves, one row each under a header, each with its remove button; a wave the
/// ocean refuses has the field its reason names framed in red and the reason on its row.
fn waves_table(ui: &mut Ui, waves: &mut Vec<fieldkit::ocean::Wave>) {
    // One row a wave under a header whose labels name each column's fields (for the eye and
    // for the accessibility tree).
    let mut remove = None;
    egui::Grid::new("waves").num_columns(7).show(ui, |ui| {
        let header = ["dir x", "dir z", "amp (m)", "λ (m)", "speed (m/s)"].map(|h| ui.label(h).id);
        ui.end_row();
        for (i, w) in waves.iter_mut().enumerate() {
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
                mark(ui, &r, bad);
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
        waves.remove(i);
    }
    if ui.button("add a wave").clicked() {
        waves.push(fieldkit::ocean::Wave {
            direction: glam::Vec2::new(0.5, 0.5),
            amplitude: 0.05,
            wavelength: 6.0,
            speed: 3.0,
        });
    }
}

/// The ocean's detail layers: each tile and strength, a refused one marked.
fn detail_layer_rows(ui: &mut Ui, look: &mut fieldkit::ocean::Look, bad: Option<Control>) {
    ui.label(format!(
        "detail layers: {} height, {} normal",
        look.height_layers.len(),
        look.normal_layers.len()
    ));
    for (name, layers, kind) in [
        (
            "height",
            &mut look.height_layers,
            Control::HeightLayer as fn(usize) -> Control,
        ),
        ("normal", &mut look.normal_layers, Control::NormalLayer),
    ] {
        for (i, l) in layers.iter_mut().enumerate() {
            let why = l.check().err();
            ui.horizontal(|ui| {
                let layer_bad = bad == Some(kind(i));
                let id = control_label(ui, &format!("{name} {i}: tile (m)"), layer_bad).id;
                let r = ui
                    .add(DragValue::new(&mut l.tile).speed(0.1))
                    .labelled_by(id);
                mark(
                    ui,
                    &r,
                    why.as_deref().is_some_and(|y| y.starts_with("tile")),
                );
                let unit = if name == "height" {
                    "strength (m)"
                } else {
                    "strength (slope ×)"
                };
                let id = ui.label(unit).id;
                let r = ui
                    .add(DragValue::new(&mut l.strength).speed(0.01))
                    .labelled_by(id);
                mark(
                    ui,
                    &r,
                    why.as_deref().is_some_and(|y| y.starts_with("strength")),
                );
            });
            if let Some(why) = &why {
                ui.colored_label(ERROR_RED, why);
            }
        }
    }
}

pub fn volume_panel(ui: &mut Ui, s: &mut VolumeSettings, bad: Option<Control>) {
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
    slider_on_release(
        ui,
        &mut s.size,
        16..=256,
        "cloud voxels per side",
        bad == Some(Control::CloudSize),
    )
    .on_hover_text("the baked cloud's resolution (4 to 512); its bricks' with the function");
    ui.horizontal(|ui| {
        let id = ui.label("noise seed").id;
        ui.add(DragValue::new(&mut s.seed))
            .labelled_by(id)
            .on_hover_text("the fBm's seed: another cloud");
    });
    ui.add(
        Slider::new(&mut s.march.step, 0.001..=0.05)
            .logarithmic(true)
            .text("step (volume units)"),
    )
    .on_hover_text("the march's step; the volume is 1 unit across");
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
    ui.checkbox(&mut s.march.skip, "empty-space skipping")
        .on_hover_text("rays jump over bricks the transfer function leaves clear");
    ui.checkbox(&mut s.march.jitter, "jitter")
        .on_hover_text("each ray starts a random fraction of a step in: noise instead of bands");
    ui.add(Slider::new(&mut s.march.ambient, 0.0..=1.0).text("ambient (0–1)"));
    vec3_row(ui, "light (direction)", &mut s.march.light_dir, 0.02);
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
        ui.label("density range (0–1)")
            .on_hover_text("the densities the transfer function spreads its colours over");
        for (end, name) in s.tf.range.iter_mut().zip(["from", "to"]) {
            let id = ui.label(name).id;
            ui.add(DragValue::new(end).speed(0.01)).labelled_by(id);
        }
    });
}

pub fn distance_panel(ui: &mut Ui, s: &mut DistanceSettings, bad: Option<Control>) {
    ui.heading("2D distance (seed 003)");
    ui.label("left button: draw seeds, right: erase");
    ComboBox::from_label("method")
        .selected_text(scenes::method_name(s.options.method))
        .show_ui(ui, |ui| {
            for m in scenes::methods_2d() {
                ui.selectable_value(&mut s.options.method, m, scenes::method_name(m));
            }
        });
    ui.checkbox(&mut s.options.signed, "signed")
        .on_hover_text("negative inside the seeds, each side measured to the other's edge");
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
    ui.add(Slider::new(&mut s.options.seeds.above, 0.0..=1.0).text("seed above (0–1)"))
        .on_hover_text("a texel is a seed where its channel is above this");
    preset_row(
        ui,
        &mut s.options.seeds,
        fieldkit::distance::SeedRule::default(),
        fieldkit::distance::SeedRule::seed(),
        "the source's rule: every non-black texel is a seed",
    );
    ui.add(Slider::new(&mut s.brush, 0..=12).text("brush radius (texels)"));
    ui.add(Slider::new(&mut s.iso_period, 1.0..=32.0).text("iso-lines every (texels)"));
    ui.horizontal(|ui| {
        let size_bad = bad == Some(Control::MaskSize);
        control_label(ui, "size (texels)", size_bad)
            .on_hover_text("the mask's width and height: each ≥ 1, at most 4096² texels");
        for (side, axis) in s.size.iter_mut().zip(["w", "h"]) {
            let id = ui.label(axis).id;
            // Not clamped: a size out of range is the scene's error, not another size.
            let r = ui
                .add(
                    DragValue::new(side)
                        .range(0..=u32::MAX)
                        .update_while_editing(false),
                )
                .labelled_by(id);
            mark(ui, &r, size_bad);
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

pub fn voxelizer_panel(ui: &mut Ui, s: &mut VoxelizerSettings, bad: Option<Control>) {
    ui.heading("voxelizer (seed 004)");
    ui.checkbox(&mut s.point_light, "point light (the source's demo scene)");
    ui.horizontal(|ui| {
        let mesh_bad = bad == Some(Control::Mesh);
        let id = control_label(ui, "mesh", mesh_bad).id;
        let r = ui
            .text_edit_singleline(&mut s.mesh)
            .labelled_by(id)
            .on_hover_text("an OBJ file's path, or torus or sphere");
        mark(ui, &r, mesh_bad);
    });
    ui.horizontal(|ui| {
        for m in ["torus", "sphere", scenes::BUNNY] {
            if ui.small_button(m.rsplit('/').next().unwrap_or(m)).clicked() {
                s.mesh = m.into();
            }
        }
    });
    // Costly to apply: taken when the drag ends or the number typed is entered.
    slider_on_release(
        ui,
        &mut s.grid,
        4..=512,
        "grid (voxels, longest side)",
        false,
    )
    .on_hover_text("voxels along the mesh's longest side; the others in proportion");
    let spin = ui.add(
        Slider::new(&mut s.spin, -std::f32::consts::PI..=std::f32::consts::PI)
            .text("spin about y (rad)"),
    );
    mark(ui, &spin, bad == Some(Control::Spin));
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
    ui.checkbox(&mut s.slice, "signed distance slice (middle z)")
        .on_hover_text(
            "the mesh's signed distance on the grid's middle z plane, drawn over the view",
        );
    ui.add(Slider::new(&mut s.band, 0.5..=16.0).text("distance band (voxels)"))
        .on_hover_text("the mesh distance field is exact within this many voxels of the surface");
}
