//! fieldkit's shader toolchain, for build scripts: find the stages of a shader folder, link their
//! WESL imports, validate them with naga (every error at its original file:line:col), reflect
//! them, lint them, and generate typed wgpu bindings. fieldkit's own `build.rs` and `xtask`
//! run it, and so can yours:
//!
//! ```no_run
//! // The body of `fn main` in the build.rs of a crate with `fieldkit` in [dependencies] and
//! // `fieldkit-build` in [build-dependencies]; its shaders anywhere under `shaders/`
//! // (`shaders/blur.wgsl` is generated as `shaders::blur`, `shaders/post/down.wgsl` as
//! // `shaders::post::down`), helpers it imports (`import package::shared::name::item;`) in
//! // `shaders/shared/`.
//! fieldkit_build::Builder::new("shaders").build_or_exit();
//! ```
//!
//! Every link has fieldkit's own helpers too, as the WESL package `fieldkit` (the `fieldkit-wesl`
//! crate): `import fieldkit::seed::pack_seed3;` (seed packing, Gerstner waves, octahedral
//! normals, triangle/box overlap, field sampling; the module tree is in `fieldkit_wesl`'s docs).
//!
//! and in the crate: `mod shaders { include!(concat!(env!("OUT_DIR"), "/shaders.rs")); }`.
//! The generated code uses `fieldkit::bind` (the runtime half: resources, pipelines, typed
//! binding errors) and derives from `bytemuck` and `encase`, which the crate depends on too.

pub mod cli;
pub mod codegen;
pub mod drift;
mod link;
pub mod lint;
#[cfg(feature = "portability")]
pub mod portability;
pub mod reflect;

use std::path::{Path, PathBuf};

pub use link::SharedDecl;
use link::{link, render, unsupported_bindings};

/// Folder under `shaders/` that holds importable helpers rather than stages.
pub const SHARED_DIR: &str = "shared";

/// A shader folder: `base.join(dir)`, stages at any depth in it ([`discover`]), helpers under
/// `shared/`. Messages name files `dir/…/file` (relative to `base`, which may be empty for a
/// path relative to the working directory).
#[derive(Debug, Clone)]
pub struct ShaderDir {
    pub base: PathBuf,
    pub dir: String,
}

impl ShaderDir {
    /// `dir` under `base`, written with forward slashes and no trailing slash.
    pub fn new(base: impl Into<PathBuf>, dir: &str) -> Self {
        let dir = dir.replace('\\', "/");
        let trimmed = dir.trim_end_matches('/');
        Self {
            base: base.into(),
            dir: if trimmed.is_empty() {
                dir
            } else {
                trimmed.to_string()
            },
        }
    }

    /// The folder on disk.
    pub fn root(&self) -> PathBuf {
        self.base.join(&self.dir)
    }
}

/// One shader stage file: everything under `shaders/` except `shaders/shared/`.
#[derive(Debug, Clone)]
pub struct StageFile {
    /// Folder under the shader folder ("distance"; "a/b" nested; "" directly in it).
    pub room: String,
    /// File stem ("jfa_step"): the stage's name.
    pub name: String,
    /// Path relative to the crate root, with forward slashes ("shaders/distance/jfa_step.wgsl").
    pub rel_path: String,
    pub abs_path: PathBuf,
    /// The stage's text where it is not a file of its own (a density march made from
    /// [`DENSITY_MARCH_TEMPLATE`] by [`Builder::density_march`]); `None` reads `abs_path`.
    pub source: Option<String>,
}

impl StageFile {
    /// The stage's text: [`Self::source`], or the file.
    pub fn text(&self) -> std::io::Result<String> {
        match &self.source {
            Some(s) => Ok(s.clone()),
            None => std::fs::read_to_string(&self.abs_path),
        }
    }

    /// `room::name` (`a::b::name` for a stage in `a/b/`, `name` for one directly in the
    /// folder), as used in messages and generated module paths.
    pub fn id(&self) -> String {
        if self.room.is_empty() {
            return self.name.clone();
        }
        format!("{}::{}", self.room.replace('/', "::"), self.name)
    }
}

/// A stage that linked and validated.
pub struct Stage {
    pub file: StageFile,
    /// Linked WGSL, as given to naga and to wgpu.
    pub source: String,
    pub module: naga::Module,
    pub info: naga::valid::ModuleInfo,
    /// Original source of the stage file itself (for header comments and lints).
    pub original: String,
    /// `wgpu::Features` the module needs (constant names), sorted.
    pub features: Vec<String>,
    /// Bindings (by name) whose layouts take a dynamic offset ([`Builder::dynamic_offset`]).
    pub dynamic_offsets: Vec<String>,
    /// Declarations imported from modules of the folder's `shared/`.
    pub shared: Vec<SharedDecl>,
}

/// Every shader file that is a stage, sorted by path for deterministic output: every `.wgsl`
/// and `.wesl` file under the folder at any depth but the folder's own `shared/` (importable
/// helpers). A file directly in the folder is the stage `name` (generated as `shaders::name`),
/// one in `a/b/` the stage `a::b::name`: module paths follow the folders. No file is passed
/// over without a word: a file whose name or folder is not a Rust identifier is an error
/// naming it.
pub fn discover(shaders: &ShaderDir) -> std::io::Result<Vec<StageFile>> {
    let mut out = Vec::new();
    walk(shaders, &shaders.root(), "", &mut out)?;
    Ok(out)
}

/// The stages of `dir` (the folder `room` under the root, `""` for the root itself): its files
/// first, then its folders', each sorted by name.
fn walk(
    shaders: &ShaderDir,
    dir: &Path,
    room: &str,
    out: &mut Vec<StageFile>,
) -> std::io::Result<()> {
    let mut entries: Vec<_> = std::fs::read_dir(dir)?.collect::<Result<_, _>>()?;
    entries.sort_by_key(|e| e.file_name());
    let mut folders = Vec::new();
    for e in entries {
        let name = e.file_name().to_string_lossy().into_owned();
        if e.file_type()?.is_dir() {
            if !(room.is_empty() && name == SHARED_DIR) {
                folders.push((e.path(), name));
            }
            continue;
        }
        let p = e.path();
        let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
        if ext != "wgsl" && ext != "wesl" {
            continue;
        }
        let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
        let rel = if room.is_empty() {
            name.clone()
        } else {
            format!("{room}/{name}")
        };
        let rel_path = format!("{}/{rel}", shaders.dir);
        let parts = room.split('/').filter(|r| !r.is_empty());
        for (depth, part) in parts.chain([stem.as_str()]).enumerate() {
            // The generated file's own top-level names are taken there.
            let taken = depth == 0 && ["groups", "shared", "ALL"].contains(&part);
            if !is_module_name(part) || taken {
                return Err(std::io::Error::new(
                    std::io::ErrorKind::InvalidInput,
                    format!(
                        "{rel_path}: `{part}` cannot name a generated module (its bindings live at \
                         the folder path; not an identifier, a Rust keyword, or one of the names \
                         the generated file takes at its top: groups, shared, ALL): rename it to \
                         lowercase letters, digits and _"
                    ),
                ));
            }
        }
        out.push(StageFile {
            rel_path,
            room: room.to_string(),
            name: stem,
            abs_path: p,
            source: None,
        });
    }
    for (path, name) in folders {
        let inner = if room.is_empty() {
            name
        } else {
            format!("{room}/{name}")
        };
        walk(shaders, &path, &inner, out)?;
    }
    Ok(())
}

/// Whether `s` can be a generated module's name: an identifier that is not a Rust keyword.
fn is_module_name(s: &str) -> bool {
    const KEYWORDS: &[&str] = &[
        "as", "async", "await", "break", "const", "continue", "crate", "dyn", "else", "enum",
        "extern", "false", "fn", "for", "gen", "if", "impl", "in", "let", "loop", "match", "mod",
        "move", "mut", "pub", "ref", "return", "self", "static", "struct", "super", "trait",
        "true", "type", "unsafe", "use", "where", "while", "abstract", "become", "box", "do",
        "final", "macro", "override", "priv", "try", "typeof", "unsized", "virtual", "yield",
    ];
    let mut chars = s.chars();
    chars
        .next()
        .is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
        && chars.all(|c| c.is_ascii_alphanumeric() || c == '_')
        && !KEYWORDS.contains(&s)
}

/// All files under the shader root (stages and helpers), for rebuild tracking.
pub fn all_shader_files(shader_root: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    let mut stack = vec![shader_root.to_path_buf()];
    while let Some(dir) = stack.pop() {
        if let Ok(rd) = std::fs::read_dir(&dir) {
            for e in rd.flatten() {
                let p = e.path();
                if p.is_dir() {
                    stack.push(p);
                } else {
                    out.push(p);
                }
            }
        }
    }
    out.sort();
    out
}

/// Link, parse and validate one stage. Errors are rendered against the original file.
pub fn build_stage(shaders: &ShaderDir, stage: &StageFile) -> Result<Stage, String> {
    let crate_root = shaders.base.as_path();
    let linked = link(shaders, stage)?;
    let original = stage
        .text()
        .map_err(|e| format!("{}: {e}", stage.rel_path))?;
    let module = naga::front::wgsl::parse_str(&linked.text).map_err(|e| {
        let labels: Vec<_> = e
            .labels()
            .map(|(s, l)| (s.to_range().unwrap_or(0..0), l.to_string()))
            .collect();
        render(crate_root, &linked, stage, e.message(), &labels, vec![])
    })?;
    // Before validation, which would refuse a binding array for a capability rather than say
    // what the bindings cannot hold.
    let unsupported = unsupported_bindings(stage, &module, &original);
    if !unsupported.is_empty() {
        return Err(unsupported.join("\n"));
    }
    // A vertex input the generated vertex struct cannot hold, or a declaration of its format
    // that cannot be, would shift every attribute after it: an error at its line, not a gap.
    let mut unmapped = Vec::new();
    for ep in module
        .entry_points
        .iter()
        .filter(|e| e.stage == naga::ShaderStage::Vertex)
    {
        if let Err(problems) = reflect::vertex::inputs(&original, &module, ep) {
            unmapped.extend(problems.into_iter().map(|(line, column, why)| {
                format!("error: {}:{line}:{column}: {why}", stage.rel_path)
            }));
        }
    }
    // A workgroup size the generated code cannot state would dispatch the wrong number of
    // groups: an error at the entry point, not `[1, 1, 1]`.
    for (ep, why) in reflect::workgroup_size_problems(&module) {
        let (line, column) = lint::locate(&original, &format!("fn {ep}"));
        unmapped.push(format!(
            "error: {}:{line}:{column}: the workgroup size of `{ep}` cannot be known: {why}",
            stage.rel_path
        ));
    }
    if !unmapped.is_empty() {
        return Err(unmapped.join("\n"));
    }
    let (capabilities, features) = needed_features(&module);
    let mut validator =
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities);
    let info = validator.validate(&module).map_err(|e| {
        let labels: Vec<_> = e
            .spans()
            .map(|(s, l)| (s.to_range().unwrap_or(0..0), l.clone()))
            .collect();
        let mut notes = Vec::new();
        let mut source: Option<&dyn std::error::Error> = std::error::Error::source(e.as_inner());
        while let Some(s) = source {
            notes.push(s.to_string());
            source = s.source();
        }
        render(
            crate_root,
            &linked,
            stage,
            &e.as_inner().to_string(),
            &labels,
            notes,
        )
    })?;
    let built = Stage {
        file: stage.clone(),
        source: linked.text,
        module,
        info,
        original,
        features,
        dynamic_offsets: Vec::new(),
        shared: linked.shared,
    };
    // Every entry point gets a pipeline, or the build says why it cannot (for a file that draws
    // with another file's vertex entry, once the folder is built: [`pair_errors`]).
    let mut dropped: Vec<String> = Vec::new();
    if codegen::pairs::declared(&built.original).is_empty() {
        dropped.extend(entry_errors(
            &built,
            codegen::pairs::dropped_entries(&built, &[]),
            "would get no pipeline: ",
        ));
        dropped.extend(entry_errors(
            &built,
            codegen::pairs::slot_conflicts(&built, &[]),
            "",
        ));
    }
    if !dropped.is_empty() {
        return Err(dropped.join("\n"));
    }
    Ok(built)
}

/// The naga capabilities wgpu grants for a device feature, as `wgpu-naga-bridge` maps them,
/// with the `wgpu::Features` constants each needs.
const FEATURE_CAPABILITIES: &[(naga::valid::Capabilities, &[&str])] = {
    use naga::valid::Capabilities as C;
    &[
        (C::IMMEDIATES, &["IMMEDIATES"]),
        (C::SHADER_FLOAT16, &["SHADER_F16"]),
        (
            C::TEXTURE_AND_SAMPLER_BINDING_ARRAY,
            &["TEXTURE_BINDING_ARRAY"],
        ),
        (C::BUFFER_BINDING_ARRAY, &["BUFFER_BINDING_ARRAY"]),
        (
            C::STORAGE_TEXTURE_BINDING_ARRAY,
            &["TEXTURE_BINDING_ARRAY", "STORAGE_RESOURCE_BINDING_ARRAY"],
        ),
        (
            C::STORAGE_BUFFER_BINDING_ARRAY,
            &["BUFFER_BINDING_ARRAY", "STORAGE_RESOURCE_BINDING_ARRAY"],
        ),
        (
            C::TEXTURE_AND_SAMPLER_BINDING_ARRAY_NON_UNIFORM_INDEXING,
            &["SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING"],
        ),
        (
            C::BUFFER_BINDING_ARRAY_NON_UNIFORM_INDEXING,
            &["UNIFORM_BUFFER_BINDING_ARRAYS"],
        ),
        (
            C::STORAGE_TEXTURE_BINDING_ARRAY_NON_UNIFORM_INDEXING,
            &["STORAGE_TEXTURE_ARRAY_NON_UNIFORM_INDEXING"],
        ),
        (
            C::STORAGE_BUFFER_BINDING_ARRAY_NON_UNIFORM_INDEXING,
            &["SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING"],
        ),
    ]
};

/// The capabilities to validate `module` with, and the `wgpu::Features` it needs: for a module
/// with binding arrays, immediates or half floats, each capability of [`FEATURE_CAPABILITIES`] whose
/// absence makes validation fail (so a binding array indexed only by constants does not ask
/// for non-uniform indexing), and the features each binding array's layout entry needs
/// (`wgpu-core` asks for them when the bind group layout is made).
pub(crate) fn needed_features(module: &naga::Module) -> (naga::valid::Capabilities, Vec<String>) {
    use naga::TypeInner;
    let base = naga::valid::Capabilities::default();
    let arrays: Vec<(&naga::GlobalVariable, naga::Handle<naga::Type>)> = module
        .global_variables
        .iter()
        .filter_map(|(_, v)| match module.types[v.ty].inner {
            TypeInner::BindingArray { base, .. } => Some((v, base)),
            _ => None,
        })
        .collect();
    let immediates = module
        .global_variables
        .iter()
        .any(|(_, v)| v.space == naga::AddressSpace::Immediate);
    let halves = module.types.iter().any(|(_, t)| match t.inner {
        TypeInner::Scalar(s)
        | TypeInner::Vector { scalar: s, .. }
        | TypeInner::Matrix { scalar: s, .. } => s.kind == naga::ScalarKind::Float && s.width == 2,
        _ => false,
    });
    if arrays.is_empty() && !immediates && !halves {
        return (base, Vec::new());
    }
    let all = FEATURE_CAPABILITIES
        .iter()
        .fold(base, |c, (cap, _)| c | *cap);
    let mut features: Vec<&str> = Vec::new();
    // Where the module is invalid anyway, the caller's validation says why.
    let valid = |caps| {
        naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps)
            .validate(module)
            .is_ok()
    };
    if valid(all) {
        for (cap, names) in FEATURE_CAPABILITIES {
            if !valid(all - *cap) {
                features.extend_from_slice(names);
            }
        }
    }
    for (var, elem) in arrays {
        features.extend_from_slice(match (var.space, &module.types[elem].inner) {
            (naga::AddressSpace::Uniform, _) => &["BUFFER_BINDING_ARRAY"][..],
            (naga::AddressSpace::Storage { .. }, _) => {
                &["BUFFER_BINDING_ARRAY", "STORAGE_RESOURCE_BINDING_ARRAY"]
            }
            (
                _,
                TypeInner::Image {
                    class: naga::ImageClass::Storage { .. },
                    ..
                },
            ) => &["TEXTURE_BINDING_ARRAY", "STORAGE_RESOURCE_BINDING_ARRAY"],
            _ => &["TEXTURE_BINDING_ARRAY"],
        });
    }
    features.sort();
    features.dedup();
    (all, features.into_iter().map(String::from).collect())
}

/// A stage from WGSL that is already linked (imports resolved), as generated code holds it in
/// `SOURCE`: parsed and validated as [`build_stage`] does the file, so its reflection is the
/// interface the host code was generated from.
pub fn stage_from_linked(file: StageFile, linked: &str) -> Result<Stage, String> {
    let module = naga::front::wgsl::parse_str(linked).map_err(|e| {
        format!(
            "{}: the linked source no longer parses: {}",
            file.rel_path,
            e.message()
        )
    })?;
    let (capabilities, features) = needed_features(&module);
    let info = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
        .validate(&module)
        .map_err(|e| {
            format!(
                "{}: the linked source no longer validates: {}",
                file.rel_path,
                e.as_inner()
            )
        })?;
    Ok(Stage {
        file,
        source: linked.to_string(),
        module,
        info,
        original: linked.to_string(),
        features,
        dynamic_offsets: Vec::new(),
        shared: Vec::new(),
    })
}

/// `(entry, why)` pairs as errors at each entry point of `stage`.
fn entry_errors(stage: &Stage, found: Vec<(String, String)>, lead: &str) -> Vec<String> {
    found
        .into_iter()
        .map(|(ep, why)| {
            let (line, column) = lint::locate(&stage.original, &format!("fn {ep}"));
            let what = if lead.is_empty() {
                format!("`{ep}`: {why}")
            } else {
                format!("entry point `{ep}` {lead}{why}")
            };
            format!("error: {}:{line}:{column}: {what}", stage.file.rel_path)
        })
        .collect()
}

/// The errors of the stages that draw with another file's vertex entry (`// draw with:
/// room::stage::entry`), once every stage of the folder is built: a declaration naming no
/// vertex entry, a fragment entry still without a pipeline, two variables on one slot.
pub fn pair_errors(stages: &[Stage]) -> Vec<String> {
    let mut errors = Vec::new();
    for stage in stages {
        if codegen::pairs::declared(&stage.original).is_empty() {
            continue;
        }
        match codegen::pairs::externals(stage, stages) {
            Err(problems) => errors.extend(problems.into_iter().map(|(line, column, why)| {
                format!("error: {}:{line}:{column}: {why}", stage.file.rel_path)
            })),
            Ok(externals) => {
                errors.extend(entry_errors(
                    stage,
                    codegen::pairs::dropped_entries(stage, &externals),
                    "would get no pipeline: ",
                ));
                errors.extend(entry_errors(
                    stage,
                    codegen::pairs::slot_conflicts(stage, &externals),
                    "",
                ));
            }
        }
    }
    errors
}

/// Build every stage of a crate's `shaders/`; on failure return *all* errors, one rendered
/// message per broken stage.
pub fn build_all(crate_root: &Path) -> Result<Vec<Stage>, Vec<String>> {
    build_dir(&ShaderDir::new(crate_root, "shaders"))
}

/// [`build_all`] for any shader folder.
pub fn build_dir(shaders: &ShaderDir) -> Result<Vec<Stage>, Vec<String>> {
    let files =
        discover(shaders).map_err(|e| vec![format!("cannot read {}/: {e}", shaders.dir)])?;
    let mut stages = Vec::new();
    let mut errors = Vec::new();
    for f in &files {
        match build_stage(shaders, f) {
            Ok(s) => stages.push(s),
            Err(e) => errors.push(e),
        }
    }
    errors.extend(pair_errors(&stages));
    if errors.is_empty() {
        Ok(stages)
    } else {
        Err(errors)
    }
}

/// A shader folder to build into generated bindings in `OUT_DIR`, from a build script.
#[derive(Debug, Clone)]
pub struct Builder {
    dir: String,
    runtime: String,
    out_file: String,
    dynamic_offsets: Vec<String>,
    deny_lints: bool,
    portability: bool,
    density_marches: Vec<(String, String)>,
}

/// fieldkit's volume march over a density function (see [`Builder::density_march`]): WESL that
/// imports `density` from [`DENSITY_MARCH_IMPORT`], which the builder replaces.
pub const DENSITY_MARCH_TEMPLATE: &str = include_str!("../templates/density_march.wesl");

/// The module [`DENSITY_MARCH_TEMPLATE`] imports `density` from, as written in it.
pub const DENSITY_MARCH_IMPORT: &str = "package::shared::density";

/// The stage text of a density march over `module` (a module path in the shader folder, as
/// `shared::cloud` or `clouds::cumulus`).
pub fn density_march_source(module: &str) -> String {
    let line = format!("import {DENSITY_MARCH_IMPORT}::density;");
    DENSITY_MARCH_TEMPLATE.replacen(&line, &format!("import package::{module}::density;"), 1)
}

impl Builder {
    /// The shader folder, relative to the crate root (`CARGO_MANIFEST_DIR`).
    pub fn new(dir: &str) -> Self {
        Self {
            dir: dir.to_string(),
            runtime: "::fieldkit".into(),
            out_file: "shaders.rs".into(),
            dynamic_offsets: Vec::new(),
            deny_lints: false,
            portability: false,
            density_marches: Vec::new(),
        }
    }

    /// Add a stage `room::name` (e.g. `"clouds::cumulus_march"`) that raymarches the density
    /// function `fn density(p: vec3<f32>) -> f32` of `module` (a WESL/WGSL module of the
    /// shader folder, written as a path: `"shared::cumulus"` for `shaders/shared/cumulus.wesl`;
    /// `p` is a point in the volume's local space). The stage is fieldkit's volume march
    /// ([`DENSITY_MARCH_TEMPLATE`]) with every sample taken from the function, linked and
    /// validated here like any stage, and generated as `shaders::room::name` with the entry
    /// points `march`, `bricks` and `bake`; `fieldkit::volume::DensityMarch` runs it. Keep the
    /// module out of the technique folders (under `shared/`) unless it has entry points of its
    /// own: every file there is a stage.
    ///
    /// ```no_run
    /// // build.rs
    /// fieldkit_build::Builder::new("shaders")
    ///     .density_march("clouds::cumulus_march", "shared::cumulus")
    ///     .build_or_exit();
    /// ```
    pub fn density_march(mut self, stage: &str, module: &str) -> Self {
        self.density_marches
            .push((stage.to_string(), module.to_string()));
        self
    }

    /// Also translate every stage to SPIR-V, MSL, HLSL and GLSL (the languages wgpu's backends
    /// take) and report a stage that does not translate as a `[portability]` finding, a warning
    /// or, with [`Self::deny_lints`], an error. Feature `portability` (naga's writers: a longer
    /// build of this crate).
    #[cfg(feature = "portability")]
    pub fn check_portability(mut self) -> Self {
        self.portability = true;
        self
    }

    /// Make the lints' findings (header comment, ascending bindings, unused bindings, workgroup
    /// and WebGPU limits; a file opts out of one with `// lint: allow(name): why`) build errors.
    /// Without it they are cargo warnings. Portability to every backend language is checked by
    /// `cargo xtask lint --shaders DIR`, which carries naga's writers.
    pub fn deny_lints(mut self) -> Self {
        self.deny_lints = true;
        self
    }

    /// Give one uniform or storage buffer binding, `room::stage::binding` (e.g.
    /// `"math::scale::params"`), a dynamic offset: its layout entry has `has_dynamic_offset`,
    /// and the offset is passed when the bind group is set (`Bound::set_compute_with_offsets`).
    /// A name that matches no buffer binding is a build error.
    pub fn dynamic_offset(mut self, binding: &str) -> Self {
        self.dynamic_offsets.push(binding.to_string());
        self
    }

    /// The path the generated code reaches fieldkit's runtime types by (`::fieldkit` unless set;
    /// fieldkit itself uses `crate`).
    pub fn runtime(mut self, path: &str) -> Self {
        self.runtime = path.to_string();
        self
    }

    /// The generated file's name in `OUT_DIR` (`shaders.rs` unless set).
    pub fn out_file(mut self, name: &str) -> Self {
        self.out_file = name.to_string();
        self
    }

    /// Build every stage and write the bindings to `OUT_DIR`, telling cargo to rerun when the
    /// folder changes. Returns the file written, or every stage's errors.
    pub fn build(&self) -> Result<PathBuf, Vec<String>> {
        let root = PathBuf::from(
            std::env::var("CARGO_MANIFEST_DIR")
                .map_err(|e| vec![format!("CARGO_MANIFEST_DIR: {e}")])?,
        );
        let out =
            PathBuf::from(std::env::var("OUT_DIR").map_err(|e| vec![format!("OUT_DIR: {e}")])?)
                .join(&self.out_file);
        // A directory here makes cargo rerun when any file under it changes.
        println!("cargo:rerun-if-changed={}", self.dir);
        let (path, findings) = self.build_linted(&root, &out)?;
        for f in &findings {
            println!("cargo:warning={f}");
        }
        Ok(path)
    }

    /// [`Self::build`] from `crate_root` into `out`, without cargo's environment (lint
    /// findings are errors only with [`Self::deny_lints`]).
    pub fn build_to(&self, crate_root: &Path, out: &Path) -> Result<PathBuf, Vec<String>> {
        self.build_linted(crate_root, out).map(|(p, _)| p)
    }

    /// [`Self::build_to`], and the lints' findings (`file:line:col: [lint] message`), which
    /// are the error where [`Self::deny_lints`] is set.
    fn build_linted(
        &self,
        crate_root: &Path,
        out: &Path,
    ) -> Result<(PathBuf, Vec<String>), Vec<String>> {
        let shaders = ShaderDir::new(crate_root, &self.dir);
        let mut stages = build_dir(&shaders)?;
        let mut errors = Vec::new();
        for (id, module) in &self.density_marches {
            let valid = |s: &str| {
                !s.is_empty()
                    && s.split("::").all(|p| {
                        !p.is_empty()
                            && p.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                            && !p.starts_with(|c: char| c.is_ascii_digit())
                    })
            };
            let Some((room, name)) = id
                .split_once("::")
                .filter(|(r, n)| valid(r) && valid(n) && !n.contains("::") && *r != SHARED_DIR)
            else {
                errors.push(format!(
                    "error: density_march(\"{id}\", …): name the stage room::name (a technique \
                     folder and a stage name, not under {SHARED_DIR}/)"
                ));
                continue;
            };
            if !valid(module) {
                errors.push(format!(
                    "error: density_march(…, \"{module}\"): name the density module by its path \
                     in {}/, as shared::cloud",
                    self.dir
                ));
                continue;
            }
            if stages.iter().any(|s| s.file.id() == *id) {
                errors.push(format!(
                    "error: density_march(\"{id}\", …): {}/{room}/{name} is already a stage file",
                    self.dir
                ));
                continue;
            }
            let file = StageFile {
                room: room.to_string(),
                name: name.to_string(),
                rel_path: format!("{}/{room}/{name}.wesl", self.dir),
                abs_path: shaders.root().join(room).join(format!("{name}.wesl")),
                source: Some(density_march_source(module)),
            };
            match build_stage(&shaders, &file) {
                Ok(stage) => stages.push(stage),
                Err(e) => errors.push(format!(
                    "{e}\n(in the density march `{id}` over the module `{module}`)"
                )),
            }
        }
        stages.sort_by(|a, b| a.file.rel_path.cmp(&b.file.rel_path));
        for name in &self.dynamic_offsets {
            let (stage_id, binding) = name.rsplit_once("::").unwrap_or(("", name));
            let Some(stage) = stages.iter_mut().find(|s| s.file.id() == stage_id) else {
                errors.push(format!(
                    "error: dynamic_offset(\"{name}\"): no stage `{stage_id}` in {}/ \
                     (name a binding as room::stage::binding)",
                    self.dir
                ));
                continue;
            };
            let is_buffer = stage.module.global_variables.iter().any(|(_, v)| {
                v.name.as_deref() == Some(binding)
                    && v.binding.is_some()
                    && matches!(
                        v.space,
                        naga::AddressSpace::Uniform | naga::AddressSpace::Storage { .. }
                    )
                    && !matches!(
                        stage.module.types[v.ty].inner,
                        naga::TypeInner::BindingArray { .. }
                    )
            });
            if !is_buffer {
                errors.push(format!(
                    "error: dynamic_offset(\"{name}\"): {} has no uniform or storage buffer \
                     binding `{binding}` (only those take a dynamic offset)",
                    stage.file.rel_path
                ));
                continue;
            }
            stage.dynamic_offsets.push(binding.to_string());
        }
        errors.extend(pair_errors(&stages));
        if !errors.is_empty() {
            return Err(errors);
        }
        let mut findings: Vec<String> = stages
            .iter()
            .flat_map(|st| lint::run(st, &reflect::reflect(st)))
            .map(|v| v.to_string())
            .collect();
        findings.extend(self.portability_findings(&stages));
        if self.deny_lints && !findings.is_empty() {
            return Err(findings);
        }
        let code = codegen::generate_for(&stages, &self.runtime);
        // Only touch the file when it changes, so dependents are not rebuilt for nothing.
        if std::fs::read_to_string(out).ok().as_deref() != Some(code.as_str()) {
            std::fs::write(out, code).map_err(|e| vec![format!("{}: {e}", out.display())])?;
        }
        Ok((out.to_path_buf(), findings))
    }

    /// With [`Self::check_portability`], each stage that does not translate to a backend
    /// language, as a `[portability]` finding.
    fn portability_findings(&self, stages: &[Stage]) -> Vec<String> {
        #[cfg_attr(not(feature = "portability"), allow(unused_mut))]
        let mut out = Vec::new();
        if !self.portability {
            return out;
        }
        #[cfg(feature = "portability")]
        for st in stages {
            for (lang, result) in portability::translate_all(st) {
                if let Err(e) = result {
                    out.push(format!(
                        "{}:1:1: [portability] cannot translate to {lang}: {e}",
                        st.file.rel_path
                    ));
                }
            }
        }
        #[cfg(not(feature = "portability"))]
        let _ = stages;
        out
    }

    /// [`Self::build`], and on failure every error as a cargo warning and on stderr, then exit
    /// with status 1 (what a build script wants).
    pub fn build_or_exit(&self) -> PathBuf {
        match self.build() {
            Ok(p) => p,
            Err(errors) => {
                for e in &errors {
                    for line in e.lines() {
                        println!("cargo:warning={line}");
                    }
                    eprintln!("{e}");
                }
                eprintln!("{} shader(s) failed to validate", errors.len());
                std::process::exit(1);
            }
        }
    }
}

#[cfg(test)]
mod tests;
