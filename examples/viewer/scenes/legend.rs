//! What the colours of a debug view mean: the legend the viewer draws over it. The ramps are
//! the colours the views draw, sampled from the same formulas (the shaders' `heat` and the
//! SDF view's red and blue; the 2D tool's and the slice's own colour functions), and the
//! viewer's tests hold rendered debug views to them.

use fieldkit::metaball::Output as MarchOutput;

use super::{ActorDraw, Saved, VoxelMode, distance2d::field_base, voxelizer::slice_base};

/// Samples a ramp takes, low end to high end.
pub const RAMP_SAMPLES: usize = 33;

/// One debug view's legend.
#[derive(Clone, Debug, PartialEq)]
pub struct Legend {
    /// What the view shows.
    pub title: String,
    /// Colours from the low end to the high end, evenly spaced (empty: keys only).
    pub ramp: Vec<[u8; 3]>,
    /// What the ramp's low and high ends stand for.
    pub ends: [String; 2],
    /// Single colours and what each means.
    pub keys: Vec<([u8; 3], String)>,
}

/// The shaders' heat ramp (`shared::shading::heat`): black → red → yellow → white over [0, 1].
pub fn heat(x: f32) -> [u8; 3] {
    let t = x.clamp(0.0, 1.0);
    [3.0 * t, 3.0 * t - 1.0, 3.0 * t - 2.0].map(|c| (c.clamp(0.0, 1.0) * 255.0).round() as u8)
}

/// The SDF view's colour of a distance `s` in bands (−1 inside … +1 outside): red outside,
/// blue inside, green 0.2 (`sdf_raymarch.wgsl`, output 4).
pub fn sdf_colour(s: f32) -> [u8; 3] {
    [s.max(0.0), 0.2, (-s).max(0.0)].map(|c| (c.min(1.0) * 255.0).round() as u8)
}

fn ramp(f: impl Fn(f32) -> [u8; 3]) -> Vec<[u8; 3]> {
    (0..RAMP_SAMPLES)
        .map(|i| f(i as f32 / (RAMP_SAMPLES - 1) as f32))
        .collect()
}

impl Saved {
    /// The legends of what `scene` draws now with these settings, one per debug view shown
    /// (none for a lit picture).
    pub fn legends(&self, scene: &str) -> Vec<Legend> {
        match scene {
            "actor" => self.actor_legend().into_iter().collect(),
            "ocean" => self.ocean_legends(),
            "distance2d" => vec![self.distance_legend()],
            "voxelizer" => self.voxelizer_legends(),
            _ => Vec::new(),
        }
    }

    fn actor_legend(&self) -> Option<Legend> {
        let a = &self.actor;
        if a.draw == ActorDraw::Cubes {
            return None;
        }
        let direct = matches!(a.draw, ActorDraw::Direct(_));
        Some(match a.raymarch.output {
            MarchOutput::Steps => Legend {
                title: "steps per ray".into(),
                ramp: ramp(heat),
                ends: [
                    "0".into(),
                    if direct {
                        format!("the cap ({} × the grid's scale)", a.raymarch.max_steps)
                    } else {
                        format!("{}, the cap", a.raymarch.max_steps)
                    },
                ],
                keys: Vec::new(),
            },
            MarchOutput::Density => Legend {
                title: "density just inside the surface".into(),
                ramp: ramp(heat),
                ends: [
                    "0".into(),
                    format!("{:.2} (4 × the threshold)", 4.0 * a.field.threshold),
                ],
                keys: Vec::new(),
            },
            MarchOutput::Sdf => Legend {
                title: "signed distance where the ray enters the box".into(),
                ramp: ramp(|t| sdf_colour(2.0 * t - 1.0)),
                ends: [
                    format!("−{} cells (inside)", a.field.band),
                    format!("+{} cells (outside)", a.field.band),
                ],
                keys: Vec::new(),
            },
            _ => return None,
        })
    }

    fn ocean_legends(&self) -> Vec<Legend> {
        let mut out = Vec::new();
        let keys = |title: &str, keys: &[([u8; 3], &str)]| Legend {
            title: title.into(),
            ramp: Vec::new(),
            ends: [String::new(), String::new()],
            keys: keys.iter().map(|(c, k)| (*c, k.to_string())).collect(),
        };
        match self.ocean.gbuffer {
            Some(0) => out.push(keys(
                "G-buffer 0: scene colour (the water's own light)",
                &[],
            )),
            Some(1) => out.push(keys(
                "G-buffer 1: normal, rgb = xyz × ½ + ½",
                &[
                    ([255, 128, 128], "+x"),
                    ([128, 255, 128], "+y (up)"),
                    ([128, 128, 255], "+z"),
                ],
            )),
            Some(2) => out.push(keys(
                "G-buffer 2: material",
                &[
                    ([255, 0, 0], "r metallic"),
                    ([0, 255, 0], "g specular"),
                    ([0, 0, 255], "b roughness"),
                ],
            )),
            Some(3) => out.push(keys("G-buffer 3: base colour", &[])),
            _ => {}
        }
        if self.ocean.overlay {
            out.push(keys(
                "patch quadtree",
                &[([255, 217, 51], "a patch's outline")],
            ));
        }
        out
    }

    fn distance_legend(&self) -> Legend {
        let d = &self.distance;
        let base = |t: f32| field_base(t).map(|c| c as u8);
        let (ramp, low) = if d.options.signed {
            (ramp(|t| base(128.0 * t - 64.0)), "−64 texels (inside)")
        } else {
            (ramp(|t| base(64.0 * t)), "0")
        };
        Legend {
            title: "distance to the nearest seed".into(),
            ramp,
            ends: [low.into(), "64 texels and beyond".into()],
            keys: vec![
                ([255, 255, 255], "a seed".into()),
                (
                    [64, 64, 64],
                    format!("an iso-line every {} texels", d.iso_period),
                ),
                ([255, 0, 255], "wrong against the exact transform".into()),
            ],
        }
    }

    fn voxelizer_legends(&self) -> Vec<Legend> {
        let v = &self.voxelizer;
        let mut out = Vec::new();
        if v.mode != VoxelMode::DistanceField && v.colour_by == fieldkit::voxelize::ColourBy::Normal
        {
            out.push(Legend {
                title: "voxels coloured by normal, rgb = xyz × ½ + ½, lit".into(),
                ramp: Vec::new(),
                ends: [String::new(), String::new()],
                keys: vec![
                    ([255, 128, 128], "+x".into()),
                    ([128, 255, 128], "+y".into()),
                    ([128, 128, 255], "+z".into()),
                ],
            });
        }
        if v.slice {
            let band = v.band;
            out.push(Legend {
                title: "signed distance, the middle z slice (lower right)".into(),
                ramp: ramp(|t| slice_base(band * (2.0 * t - 1.0), band)),
                ends: [
                    format!("−{band} voxels (inside)"),
                    format!("+{band} voxels (outside)"),
                ],
                keys: vec![
                    ([255, 255, 255], "the surface (within ¼ voxel)".into()),
                    ([140, 140, 140], "a line every voxel".into()),
                ],
            });
        }
        out
    }
}
