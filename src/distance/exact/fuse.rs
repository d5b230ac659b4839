//! Which entry point of a column-pass family a resolving pass takes ([`Resolve`]), and the macro
//! that records the one it names.

use crate::distance::resolve::Fuse;

/// Which entry point of a column-pass family a pass takes, and what its resolve writes.
#[derive(Clone, Copy)]
pub(crate) enum Resolve<'a> {
    /// The nearest seeds alone (`columns`, `tile_columns`).
    No,
    /// Distances into a 2D (`*_resolve_2d`) or 3D (`*_resolve`) view: signed (the shader's
    /// SIGNED) where the inside seeds' field is given beside it.
    Flat(Option<&'a wgpu::Buffer>, &'a wgpu::TextureView),
    Volume(Option<&'a wgpu::Buffer>, &'a wgpu::TextureView),
}

impl<'a> Resolve<'a> {
    /// The entry point a column pass writing slab `slab` takes for `fuse`.
    pub(crate) fn of(fuse: Option<&Fuse<'a>>, slab: usize) -> Self {
        match fuse {
            None => Resolve::No,
            Some(f) => {
                let inside = f.inside_field.map(|inside| &inside[slab]);
                match f.flat {
                    true => Resolve::Flat(inside, f.distance),
                    false => Resolve::Volume(inside, f.distance),
                }
            }
        }
    }
}

/// Records the entry point of a column-pass family that `$resolve` (a [`Resolve`]) names,
/// through the caller's `$record!(cache, entry { extra resources })`: the three entries in the
/// order No, Flat, Volume, each `cache => entry`; `$unsigned` is bound as `nearest_inside` where
/// the resolve is not signed (the shader does not read it then).
macro_rules! record_resolved {
    ($record:ident, $resolve:expr, $unsigned:expr, $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, $unsigned, {}, $($cache => $entry),*)
    };
    // The volume entries bind more (`edt_columns.wgsl`'s `swept`).
    ($record:ident, $resolve:expr, $unsigned:expr, volume { $($field:ident: $value:expr),* },
        $($cache:expr => $entry:ident),* $(,)?) => {
        record_resolved!(@arms $record, $resolve, $unsigned, { $($field: $value),* },
            $($cache => $entry),*)
    };
    (@arms $record:ident, $resolve:expr, $unsigned:expr, { $($field:ident: $value:expr),* },
        $c0:expr => $e0:ident, $c1:expr => $e1:ident, $c2:expr => $e2:ident) => {
        match $resolve {
            Resolve::No => $record!($c0, $e0 {}),
            Resolve::Flat(i, d) => {
                $record!($c1, $e1 { nearest_inside: i.unwrap_or($unsigned), distance_2d: d })
            }
            Resolve::Volume(i, d) => $record!($c2, $e2 {
                nearest_inside: i.unwrap_or($unsigned), distance: d $(, $field: $value)*
            }),
        }
    };
}
