//! Which entry point of a column-pass family a resolving pass takes ([`Resolve`]), and the macro
//! that records the one it names.

use crate::distance::resolve::Fuse;

/// Which entry point of a column-pass family a pass takes, and what its resolve writes.
pub(crate) enum Resolve<'a> {
    /// The nearest seeds alone (`columns`, `tile_columns`).
    No,
    /// Unsigned distances into a 2D (`*_resolve_2d`) or 3D (`*_resolve`) view.
    Flat(&'a wgpu::TextureView),
    Volume(&'a wgpu::TextureView),
    /// Signed (`*_resolve_signed_2d`, `*_resolve_signed`): the inside seeds' field beside it.
    SignedFlat(&'a wgpu::Buffer, &'a wgpu::TextureView),
    SignedVolume(&'a wgpu::Buffer, &'a wgpu::TextureView),
}

impl<'a> Resolve<'a> {
    /// The entry point a column pass writing slab `slab` takes for `fuse`.
    pub(crate) fn of(fuse: Option<&Fuse<'a>>, slab: usize) -> Self {
        match fuse {
            None => Resolve::No,
            Some(f) => match (f.flat, f.inside_field) {
                (true, None) => Resolve::Flat(f.distance),
                (false, None) => Resolve::Volume(f.distance),
                (true, Some(inside)) => Resolve::SignedFlat(&inside[slab], f.distance),
                (false, Some(inside)) => Resolve::SignedVolume(&inside[slab], f.distance),
            },
        }
    }
}

/// Records the entry point of a column-pass family that `$resolve` (a [`Resolve`]) names,
/// through the caller's `$record!(cache, entry { extra resources })`: the five entries in the
/// order No, Flat, SignedFlat, Volume, SignedVolume, each `cache => entry`.
macro_rules! record_resolved {
    ($record:ident, $resolve:expr, $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, {}, $($cache => $entry),*)
    };
    // The volume entries bind more (`edt_columns.wgsl`'s `swept`).
    ($record:ident, $resolve:expr, volume { $($field:ident: $value:expr),* },
        $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, { $($field: $value),* }, $($cache => $entry),*)
    };
    (@arms $record:ident, $resolve:expr, { $($field:ident: $value:expr),* },
        $c0:expr => $e0:ident, $c1:expr => $e1:ident, $c2:expr => $e2:ident,
        $c3:expr => $e3:ident, $c4:expr => $e4:ident) => {
        match $resolve {
            Resolve::No => $record!($c0, $e0 {}),
            Resolve::Flat(d) => $record!($c1, $e1 { distance_2d: d }),
            Resolve::SignedFlat(i, d) => $record!($c2, $e2 { nearest_inside: i, distance_2d: d }),
            Resolve::Volume(d) => $record!($c3, $e3 { distance: d $(, $field: $value)* }),
            Resolve::SignedVolume(i, d) => {
                $record!($c4, $e4 { nearest_inside: i, distance: d $(, $field: $value)* })
            }
        }
    };
}
