//! The settings changes the viewer's panels offer whose first use could make GPU objects: every
//! choice (a draw mode, a method, an output, a target), every switch, the seed presets and the
//! camera's depth convention, each one step from the settings given. `--frame-cost` times the
//! frame of each and the frames after it; a test holds each of those frames to no pipeline
//! made on it (what a change needs is made on a worker thread, or was made up front).
//!
//! Sliders are left out: they move numbers the shaders read as uniforms. The grid, mask and
//! cloud sizes are [`super::frame::size_change`]'s.

use fieldkit::distance::{Channels, Method, Variant};
use fieldkit::metaball::{Direct, ExactSurface, Output as MarchOutput};
use fieldkit::volume::{Mode, Shadow};
use fieldkit::voxelize::{ColourBy, Separation};

use super::scenes::{
    ActorDraw, ActorSettings, NAMES, OceanSettings, Saved, VolumeSettings, VoxelMode,
};

/// Each settings change `scene`'s panel offers from `saved`: its name and the settings after
/// it. A choice `saved` already holds is left out.
pub fn setting_changes(scene: &str, saved: &Saved) -> Vec<(String, Saved)> {
    let mut out = Vec::new();
    let mut push = |name: String, s: Saved| {
        if s != *saved {
            out.push((name, s));
        }
    };
    match scene {
        "actor" => actor(saved, &mut push),
        "ocean" => ocean(saved, &mut push),
        "volume" => volume(saved, &mut push),
        "distance2d" => distance(saved, &mut push),
        "voxelizer" => voxelizer(saved, &mut push),
        _ => composite(saved, &mut push),
    }
    let mut s = saved.clone();
    // The voxelizer's distance field: its lit voxel view has no reversed Z (a typed error).
    if scene == "voxelizer" {
        s.voxelizer.mode = VoxelMode::DistanceField;
    }
    if let Some(i) = NAMES.iter().position(|n| *n == scene)
        && let Some(c) = s.cameras.get_mut(i)
    {
        c.reversed_z = !c.reversed_z;
        push("camera: reversed Z switched".into(), s);
    }
    out
}

/// One change: its name and the settings after it.
type Push<'a> = dyn FnMut(String, Saved) + 'a;

/// An edit of the settings, by name.
type Edit = (&'static str, fn(&mut Saved));

/// `saved` with `edit` applied to a copy.
fn with(saved: &Saved, edit: impl FnOnce(&mut Saved)) -> Saved {
    let mut s = saved.clone();
    edit(&mut s);
    s
}

/// Each of `edits` from `saved`.
fn each(saved: &Saved, push: &mut Push, edits: &[Edit]) {
    for (name, edit) in edits {
        push(name.to_string(), with(saved, edit));
    }
}

/// A choice of `values` from `saved`, each set by `set` and named `label: value`.
fn choose<T: Copy + std::fmt::Debug>(
    saved: &Saved,
    push: &mut Push,
    label: &str,
    values: &[T],
    set: fn(&mut Saved, T),
) {
    for &v in values {
        push(format!("{label}: {v:?}"), with(saved, |s| set(s, v)));
    }
}

fn actor(saved: &Saved, push: &mut Push) {
    let draws = [
        ActorDraw::Surface,
        ActorDraw::Cubes,
        ActorDraw::Both,
        ActorDraw::Direct(Direct::SphereGlobal),
        ActorDraw::Direct(Direct::Segment),
    ];
    choose(saved, push, "draw", &draws, |s, d| s.actor.draw = d);
    let methods = [
        Method::Lines,
        Method::Jfa(Variant::Jfa),
        Method::Jfa(Variant::JfaPlus1),
        Method::Jfa(Variant::JfaPlus2),
        Method::Jfa(Variant::OnePlusJfa),
    ];
    choose(saved, push, "SDF method", &methods, |s, m| {
        s.actor.field.method = m
    });
    let outputs = [
        MarchOutput::Shaded,
        MarchOutput::Sdf,
        MarchOutput::Density,
        MarchOutput::Steps,
    ];
    choose(saved, push, "view", &outputs, |s, o| {
        s.actor.raymarch.output = o
    });
    let exact = [ExactSurface::On, ExactSurface::Off];
    choose(saved, push, "exact surface", &exact, |s, e| {
        s.actor.field.exact_surface = e
    });
    each(
        saved,
        push,
        &[
            // The full volume is a JFA field's choice.
            ("full volume switched (JFA)", |s| {
                s.actor.field.method = Method::Jfa(Variant::JfaPlus1);
                s.actor.field.full_volume ^= true;
            }),
            ("animate switched", |s| s.actor.animate ^= true),
            ("seed preset", |s| s.actor = ActorSettings::seed()),
        ],
    );
    // The cube style's, with the cubes drawn.
    let cubes: [Edit; 7] = [
        ("cubes: wireframe switched", |s| {
            s.actor.cubes.wireframe ^= true
        }),
        ("cubes: depth write switched", |s| {
            s.actor.cubes.depth_write ^= true
        }),
        ("cubes: depth compare Always", |s| {
            s.actor.cubes.depth_compare = wgpu::CompareFunction::Always
        }),
        ("cubes: both faces", |s| s.actor.cubes.cull = None),
        ("cubes: colour", |s| s.actor.cubes.colour.x = 0.9),
        ("cubes: scale size switched", |s| {
            s.actor.cubes.scale_size ^= true
        }),
        ("cubes: frustum cull switched", |s| {
            s.actor.cubes.frustum_cull ^= true
        }),
    ];
    let both = with(saved, |s| s.actor.draw = ActorDraw::Both);
    each(&both, push, &cubes);
}

fn ocean(saved: &Saved, push: &mut Push) {
    let targets = [None, Some(0), Some(1), Some(2), Some(3)];
    choose(saved, push, "target", &targets, |s, g| s.ocean.gbuffer = g);
    each(
        saved,
        push,
        &[
            ("depth fade switched", |s| s.ocean.fade ^= true),
            ("patch overlay switched", |s| s.ocean.overlay ^= true),
            ("depth write off", |s| s.ocean.depth_write = Some(false)),
            ("seed preset", |s| s.ocean = OceanSettings::seed()),
        ],
    );
}

fn volume(saved: &Saved, push: &mut Push) {
    each(
        saved,
        push,
        &[
            ("function switched", |s| s.volume.function ^= true),
            ("seed preset", |s| s.volume = VolumeSettings::seed()),
        ],
    );
    march_changes(saved, push, "");
}

/// The volume march's choices and switches, named after `prefix`. A mode or shadow keeps its
/// numbers (the iso-level, the shadow step) while its kind is kept, as the panel does.
fn march_changes(saved: &Saved, push: &mut Push, prefix: &str) {
    let modes = [
        Mode::EmissionAbsorption,
        Mode::MaximumIntensity,
        Mode::IsoSurface { iso: 0.3 },
    ];
    let shadows = [
        Shadow::None,
        Shadow::Rays { step: 0.02 },
        Shadow::LightVolume { step: 0.02 },
    ];
    let kind = std::mem::discriminant::<Mode>;
    let modes: Vec<Mode> = modes
        .into_iter()
        .filter(|m| kind(m) != kind(&saved.volume.march.mode))
        .collect();
    let kind = std::mem::discriminant::<Shadow>;
    let shadows: Vec<Shadow> = shadows
        .into_iter()
        .filter(|m| kind(m) != kind(&saved.volume.march.shadow))
        .collect();
    choose(saved, push, &format!("{prefix}mode"), &modes, |s, m| {
        s.volume.march.mode = m
    });
    let label = format!("{prefix}shadow");
    choose(saved, push, &label, &shadows, |s, m| {
        s.volume.march.shadow = m
    });
    let switches: [Edit; 2] = [
        ("empty-space skipping switched", |s| {
            s.volume.march.skip ^= true
        }),
        ("jitter switched", |s| s.volume.march.jitter ^= true),
    ];
    for (name, edit) in switches {
        push(format!("{prefix}{name}"), with(saved, edit));
    }
}

fn distance(saved: &Saved, push: &mut Push) {
    for m in super::scenes::methods_2d() {
        let name = format!("method: {}", super::scenes::method_name(m));
        push(name, with(saved, |s| s.distance.options.method = m));
    }
    let channels = [Channels::Red, Channels::AnyColour, Channels::Alpha];
    let set: fn(&mut Saved, Channels) = |s, c| s.distance.options.seeds.channels = c;
    choose(saved, push, "seed channels", &channels, set);
    each(
        saved,
        push,
        &[("signed switched", |s| s.distance.options.signed ^= true)],
    );
}

fn voxelizer(saved: &Saved, push: &mut Push) {
    let modes = [
        VoxelMode::Surface(Separation::Conservative),
        VoxelMode::Surface(Separation::Six),
        VoxelMode::Raster,
        VoxelMode::Solid,
        VoxelMode::DistanceField,
    ];
    choose(saved, push, "mode", &modes, |s, m| s.voxelizer.mode = m);
    let by = [ColourBy::Normal, ColourBy::Colour];
    choose(saved, push, "colour by", &by, |s, c| {
        s.voxelizer.colour_by = c
    });
    each(
        saved,
        push,
        &[
            ("slice switched", |s| s.voxelizer.slice ^= true),
            ("point light switched", |s| s.voxelizer.point_light ^= true),
        ],
    );
}

/// The composite draws the ocean, the actor's island and the cloud: the choices those read.
fn composite(saved: &Saved, push: &mut Push) {
    each(
        saved,
        push,
        &[
            ("ocean: depth fade switched", |s| s.ocean.fade ^= true),
            ("island: SDF method Lines", |s| {
                s.actor.field.method = Method::Lines
            }),
            ("island: view Steps", |s| {
                s.actor.raymarch.output = MarchOutput::Steps
            }),
            ("cloud: function switched", |s| s.volume.function ^= true),
        ],
    );
    march_changes(saved, push, "cloud: ");
}
