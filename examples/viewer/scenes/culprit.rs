//! Which control a scene's error came from, so that the panel marks it: the scene's own
//! checks run again on the settings (they are cheap), and the voxelizer names the mesh it
//! could not load.

use super::{Saved, Scenes};

/// A control of a scene's panel that the scene's error can come from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Control {
    /// The actor's Extent (too many blocks, or not finite).
    Extent,
    /// The actor's BlockSize (zero, negative or not finite).
    BlockSize,
    /// The 2D tool's mask size.
    MaskSize,
    /// The volume's cloud voxels per side.
    CloudSize,
    /// The voxelizer's mesh (a file it could not load).
    Mesh,
    /// The voxelizer's spin (not finite).
    Spin,
    /// The ocean's wave of this index.
    Wave(usize),
    /// The ocean's height detail layer of this index.
    HeightLayer(usize),
    /// The ocean's normal detail layer of this index.
    NormalLayer(usize),
}

impl Scenes {
    /// The control behind the error `scene` reported with settings `s` (call it only when
    /// there is one): the first of the scene's settings its checks refuse. `None` where the
    /// error is not one setting's (a device limit, say).
    pub fn culprit(&self, scene: &str, s: &Saved) -> Option<Control> {
        match scene {
            "actor" => actor(s),
            "ocean" => ocean(s),
            "volume" => volume(s),
            "distance2d" => s.distance.check_size().err().map(|_| Control::MaskSize),
            "voxelizer" => {
                let v = &s.voxelizer;
                if !v.spin.is_finite() {
                    return Some(Control::Spin);
                }
                // The mesh it was asked for is not the one it holds: loading it failed.
                let loaded = self.voxelizer.as_ref().and_then(|x| x.mesh.as_ref());
                (loaded.map(|m| m.0.as_str()) != Some(v.mesh.as_str())).then_some(Control::Mesh)
            }
            // The island's extent is the composite's own; the sea and the cloud are edited
            // here.
            _ => ocean(s).or_else(|| volume(s)),
        }
    }
}

fn actor(s: &Saved) -> Option<Control> {
    let a = &s.actor;
    a.counts().err()?;
    Some(if a.block.is_finite() && a.block > 0.0 {
        Control::Extent
    } else {
        Control::BlockSize
    })
}

fn ocean(s: &Saved) -> Option<Control> {
    let o = &s.ocean;
    let bad = |layers: &[fieldkit::ocean::Layer]| layers.iter().position(|l| l.check().is_err());
    o.waves
        .iter()
        .position(|w| w.check().is_err())
        .map(Control::Wave)
        .or_else(|| bad(&o.look.height_layers).map(Control::HeightLayer))
        .or_else(|| bad(&o.look.normal_layers).map(Control::NormalLayer))
}

fn volume(s: &Saved) -> Option<Control> {
    (!(4..=512).contains(&s.volume.size)).then_some(Control::CloudSize)
}
