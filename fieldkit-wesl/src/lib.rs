//! fieldkit's WGSL helpers as a WESL package, `fieldkit`: what fieldkit's own stages import,
//! for a user's shaders to import the same way (`fieldkit::…`).
//!
//! `fieldkit-build` adds [`PACKAGE`] to every link, so a shader built by it may write
//!
//! ```wgsl
//! import fieldkit::seed::{pack_seed3, unpack_seed3};
//! ```
//!
//! With wesl alone: `wesl::Wesl::new("shaders").add_package(&fieldkit_wesl::PACKAGE)`.
//!
//! # The module tree (public API)
//!
//! | module | what it holds |
//! |---|---|
//! | `fieldkit::seed` | seed packing as the distance stages store it: 2D 16/16 bits, 3D 11/11/10 bits + 1 (`pack_seed2/3`, `unpack_seed2/3`, `NO_SEED`), squared distances, sub-voxel seed keys, signed distances from two fields |
//! | `fieldkit::gerstner` | the Gerstner wave sum the ocean displaces by (`GerstnerWave`, positions, normals) |
//! | `fieldkit::octahedral` | unit vectors packed as two snorm16 by the octahedral map (`NO_NORMAL` for none) |
//! | `fieldkit::triangle_box` | Schwarz & Seidel's triangle/voxel overlap |
//! | `fieldkit::field` | trilinear field sampling by `textureLoad` and ray/box helpers |
//! | `fieldkit::octree` | the sparse voxel octree's layout: octants, children, brick bits (`octree_child`, `brick_has`) |
//! | `fieldkit::march` | the volume march's view ray and depth stop, jittered segment lattice, segment opacity and transmittance, brick skipping |
//!
//! Each module is the file of the same name in this crate's `shaders/`, and fieldkit's own
//! stages import them from here too (`import fieldkit::seed::…`): one source, so the package
//! cannot drift from what fieldkit runs. fieldkit's internal helpers (the debug views' cube, the
//! metaball tracers' colours) stay in its `shaders/shared/` and are not part of the package.

use wesl::{CodegenModule, CodegenPkg};

macro_rules! module {
    ($name:ident) => {
        CodegenModule {
            name: stringify!($name),
            source: include_str!(concat!("../shaders/", stringify!($name), ".wesl")),
            submodules: &[],
        }
    };
}

static SEED: CodegenModule = module!(seed);
static GERSTNER: CodegenModule = module!(gerstner);
static OCTAHEDRAL: CodegenModule = module!(octahedral);
static TRIANGLE_BOX: CodegenModule = module!(triangle_box);
static FIELD: CodegenModule = module!(field);
static OCTREE: CodegenModule = module!(octree);
static MARCH: CodegenModule = module!(march);

static ROOT: CodegenModule = CodegenModule {
    name: "fieldkit",
    source: "",
    submodules: &[
        &SEED,
        &GERSTNER,
        &OCTAHEDRAL,
        &TRIANGLE_BOX,
        &FIELD,
        &OCTREE,
        &MARCH,
    ],
};

/// The `fieldkit` WESL package.
pub static PACKAGE: CodegenPkg = CodegenPkg {
    crate_name: "fieldkit",
    root: &ROOT,
    dependencies: &[],
};

/// Where the modules' files are (`SOURCE_DIR/<module>.wesl`), for tools that report an error
/// in one at its file:line:col.
pub const SOURCE_DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders");

/// The package's public modules, by name.
pub const MODULES: &[&str] = &[
    "seed",
    "gerstner",
    "octahedral",
    "triangle_box",
    "field",
    "octree",
    "march",
];

#[cfg(test)]
mod tests {
    use super::*;

    /// Every module named in the docs is in the tree, with its source.
    #[test]
    fn the_tree_holds_every_module() {
        let names: Vec<&str> = ROOT.submodules.iter().map(|m| m.name).collect();
        assert_eq!(names, MODULES);
        for m in ROOT.submodules {
            assert!(m.source.contains("fn "), "{}: no functions", m.name);
        }
    }
}
