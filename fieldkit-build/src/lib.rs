//! fieldkit's shader toolchain, for build scripts: find the stages of a shader folder, link their
//! WESL imports, validate them with naga (every error at its original file:line:col), reflect
//! them, lint them, and generate typed wgpu bindings. fieldkit's own `build.rs` and `xtask`
//! run it, and so can yours:
//!
//! ```no_run
//! // The body of `fn main` in the build.rs of a crate with `fieldkit` in [dependencies] and
//! // `fieldkit-build` in [build-dependencies]; its shaders in `shaders/<technique>/<stage>.wgsl`,
//! // helpers it imports (`import package::shared::name::item;`) in `shaders/shared/`.
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

pub mod codegen;
pub mod drift;
pub mod lint;
#[cfg(feature = "portability")]
pub mod portability;
pub mod reflect;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use codespan_reporting::diagnostic::{Diagnostic, Label};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term;

/// Folder under `shaders/` that holds importable helpers rather than stages.
pub const SHARED_DIR: &str = "shared";

/// A shader folder: `base.join(dir)`, laid out as fieldkit's `shaders/` is (one folder per
/// technique, helpers under `shared/`). Messages name files `dir/room/file` (relative to `base`,
/// which may be empty for a path relative to the working directory).
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
    /// Technique folder ("distance").
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

    /// `room::name`, as used in messages and generated module paths.
    pub fn id(&self) -> String {
        format!("{}::{}", self.room, self.name)
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

/// Every shader file that is a stage, sorted by path for deterministic output.
pub fn discover(shaders: &ShaderDir) -> std::io::Result<Vec<StageFile>> {
    let mut out = Vec::new();
    let mut rooms: Vec<_> = std::fs::read_dir(shaders.root())?.collect::<Result<_, _>>()?;
    rooms.sort_by_key(|e| e.file_name());
    for room in rooms {
        if !room.file_type()?.is_dir() || room.file_name() == SHARED_DIR {
            continue;
        }
        let room_name = room.file_name().to_string_lossy().into_owned();
        let mut files: Vec<_> = std::fs::read_dir(room.path())?.collect::<Result<_, _>>()?;
        files.sort_by_key(|e| e.file_name());
        for f in files {
            let p = f.path();
            let ext = p.extension().and_then(|e| e.to_str()).unwrap_or("");
            if ext != "wgsl" && ext != "wesl" {
                continue;
            }
            let name = p.file_stem().unwrap().to_string_lossy().into_owned();
            out.push(StageFile {
                rel_path: format!(
                    "{}/{room_name}/{}",
                    shaders.dir,
                    f.file_name().to_string_lossy()
                ),
                room: room_name.clone(),
                name,
                abs_path: p,
                source: None,
            });
        }
    }
    Ok(out)
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

/// Where a declaration of the linked output came from.
struct DeclOrigin {
    /// Byte range of the declaration in the linked text.
    linked: std::ops::Range<usize>,
    /// Original file (relative path) and the declaration's byte range in it.
    file: Option<(String, std::ops::Range<usize>)>,
}

/// Linked text plus the map back to original files.
struct Linked {
    text: String,
    origins: Vec<DeclOrigin>,
    /// Declarations from imported modules of the folder's `shared/`: mangled name, module
    /// (file stem under `shared/`), original name.
    shared: Vec<SharedDecl>,
}

/// A declaration a stage imported from a module of the folder's `shared/`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SharedDecl {
    /// Its name in the linked WGSL (mangled by WESL).
    pub linked: String,
    /// The module's path under `shared/`, with `_` between levels (`view`, `lights_sun`).
    pub module: String,
    /// Its name in the module.
    pub name: String,
}

/// Link one stage's imports with WESL and print the result declaration by declaration, keeping
/// for each its source file and span so naga's errors can be reported against the original file.
fn link(shaders: &ShaderDir, stage: &StageFile) -> Result<Linked, String> {
    let root: wesl::ModulePath = format!("package::{}::{}", stage.room, stage.name)
        .parse()
        .map_err(|e| format!("{}: bad module path: {e:?}", stage.rel_path))?;
    let mut resolver = wesl::StandardResolver::new(shaders.root());
    // fieldkit's helpers, for `import fieldkit::…` (the `fieldkit-wesl` crate).
    resolver.add_package(&fieldkit_wesl::PACKAGE);
    let original_text = stage.text().unwrap_or_default();
    let binding_arrays = binding_array_vars(&original_text);
    let mut compiler = wesl::Wesl::new(shaders.root()).set_custom_resolver(BindingArrays {
        inner: resolver,
        root: root.clone(),
        overlay: stage.source.clone(),
    });
    // Keep every declaration of the stage file itself, used or not: stripping it would drop an
    // unused binding (or a broken unused function) without a word, where the lints and naga
    // should see it. Imported helpers are still stripped to what the stage uses.
    compiler.set_options(wesl::CompileOptions {
        keep_root: true,
        ..Default::default()
    });
    compiler.use_sourcemap(true);
    let result = match compiler.compile(&root) {
        Ok(r) => r,
        Err(e) => {
            // A file that imports nothing needs no link: WGSL the pinned WESL parser does not
            // read (`binding_array` is a reserved word to wesl 0.4.0) goes to naga as it is.
            let original = stage.text().unwrap_or_default();
            if !original.is_empty() && !imports_anything(&original) {
                return Ok(Linked {
                    origins: vec![DeclOrigin {
                        linked: 0..original.len(),
                        file: Some((stage.rel_path.clone(), 0..original.len())),
                    }],
                    text: original,
                    shared: Vec::new(),
                });
            }
            return Err(format!(
                "error: WESL could not link {}\n{}",
                stage.rel_path,
                strip_ansi(&e.to_string())
            ));
        }
    };
    let sourcemap = result.sourcemap.as_ref();

    let mut text = String::new();
    for directive in &result.syntax.global_directives {
        writeln!(text, "{directive}").unwrap();
    }
    let mut origins = Vec::new();
    let mut shared = Vec::new();
    // Declarations from imported modules carry mangled names the sourcemap knows; the root
    // module's own declarations are not mangled.
    use wesl::SourceMap as _;
    use wgsl_parse::SyntaxNode as _;
    let mut decls: Vec<_> = result
        .syntax
        .global_declarations
        .iter()
        .map(|decl| {
            let found = decl.ident().and_then(|id| {
                sourcemap.and_then(|m| {
                    m.get_decl(&id.name())
                        .map(|(p, n)| (id.name().to_string(), p.clone(), n.to_string()))
                })
            });
            (decl, found)
        })
        .collect();
    // WESL 0.4.0 appends imported modules in hash-map order, which differs from run to run of
    // the same build (the linked WGSL, and so the generated file, changed between two builds
    // of one commit). Module-scope declarations may come in any order in WGSL, so print the
    // stage's own declarations first, then each imported module's in the order of its path;
    // within a module, WESL's order (the source's) is kept by the stable sort.
    decls.sort_by_cached_key(|(_, found)| found.as_ref().map(|(_, path, _)| path.to_string()));
    for (decl, found) in decls {
        if !text.is_empty() {
            text.push('\n');
        }
        let start = text.len();
        let mut printed = format!("{}", &**decl);
        // A binding array of the stage file went through WESL as `array<`: restore it.
        if let wgsl_parse::syntax::GlobalDeclaration::Declaration(d) = &**decl
            && binding_arrays.iter().any(|v| *v == *d.ident.name())
            && let Some(colon) = printed.find(':')
            && let Some(at) = printed[colon..].find("array<")
        {
            printed.insert_str(colon + at, "binding_");
        }
        text.push_str(&printed);
        let end = text.len();
        text.push('\n');
        let span = decl.span().range();
        if let Some((linked, path, name)) = &found {
            let text = path.to_string();
            if let Some(rest) = text.strip_prefix(&format!("package::{SHARED_DIR}::")) {
                shared.push(SharedDecl {
                    linked: linked.clone(),
                    module: rest.replace("::", "_"),
                    name: name.clone(),
                });
            }
        }
        let module = found.map(|(_, p, _)| p);
        let file = match module {
            Some(path) => module_file(shaders, &path),
            None => Some(stage.rel_path.clone()),
        };
        origins.push(DeclOrigin {
            linked: start..end,
            file: file.map(|f| (f, span)),
        });
    }
    Ok(Linked {
        text,
        origins,
        shared,
    })
}

/// The names of a file's `var`s declared as `binding_array<…>`.
fn binding_array_vars(source: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = source;
    while let Some(at) = rest.find("binding_array<") {
        // `var<…>? name: binding_array<`: the name is the identifier before the colon.
        let before = rest[..at].trim_end();
        if let Some(head) = before.strip_suffix(':') {
            let name: String = head
                .trim_end()
                .chars()
                .rev()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect::<Vec<_>>()
                .into_iter()
                .rev()
                .collect();
            if !name.is_empty() {
                out.push(name);
            }
        }
        rest = &rest[at + "binding_array<".len()..];
    }
    out
}

/// The standard resolver, with the stage file's `binding_array<` read as `        array<` (a
/// word the pinned WESL parser reserves, replaced by one it reads, at the same length so
/// every span still points into the original file); `link` restores the word in the stage's
/// own declarations. Imported modules are read as they are.
struct BindingArrays {
    inner: wesl::StandardResolver,
    root: wesl::ModulePath,
    /// The root module's text where it is not a file ([`StageFile::source`]).
    overlay: Option<String>,
}

impl wesl::Resolver for BindingArrays {
    fn resolve_source<'a>(
        &'a self,
        path: &wesl::ModulePath,
    ) -> Result<std::borrow::Cow<'a, str>, wesl::ResolveError> {
        let source = match &self.overlay {
            Some(text) if *path == self.root => std::borrow::Cow::Borrowed(text.as_str()),
            _ => self.inner.resolve_source(path)?,
        };
        if *path == self.root && source.contains("binding_array<") {
            return Ok(source.replace("binding_array<", "        array<").into());
        }
        Ok(source)
    }
    fn display_name(&self, path: &wesl::ModulePath) -> Option<String> {
        self.inner.display_name(path)
    }
    fn fs_path(&self, path: &wesl::ModulePath) -> Option<std::path::PathBuf> {
        self.inner.fs_path(path)
    }
}

/// Whether a WGSL/WESL file has an `import` declaration (a line that starts with one).
fn imports_anything(source: &str) -> bool {
    source.lines().any(|l| {
        l.trim_start()
            .strip_prefix("import")
            .is_some_and(|rest| rest.starts_with(char::is_whitespace))
    })
}

/// Bindings the generated host code cannot express, as errors at their declaration: binding
/// arrays without a length, external textures and acceleration structures would otherwise be
/// left out of the layouts without a word.
fn unsupported_bindings(stage: &StageFile, module: &naga::Module, original: &str) -> Vec<String> {
    use naga::TypeInner;
    module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let rb = var.binding.as_ref()?;
            let why = match &module.types[var.ty].inner {
                TypeInner::BindingArray {
                    size: naga::ArraySize::Constant(_),
                    base,
                } => match &module.types[*base].inner {
                    TypeInner::AccelerationStructure { .. } | TypeInner::BindingArray { .. } => {
                        "binding arrays of acceleration structures or of binding arrays are not \
                         supported by fieldkit's generated bindings"
                    }
                    TypeInner::Image {
                        class: naga::ImageClass::External,
                        ..
                    } => "external textures are not supported by fieldkit's generated bindings",
                    _ => return None,
                },
                TypeInner::BindingArray { .. } => {
                    "a binding array needs a length here (`binding_array<T, N>`): its bind group \
                     layout holds a count"
                }
                TypeInner::Image {
                    class: naga::ImageClass::External,
                    ..
                } => "external textures are not supported by fieldkit's generated bindings",
                TypeInner::AccelerationStructure { .. } => {
                    "acceleration structures are not supported by fieldkit's generated bindings"
                }
                _ => return None,
            };
            let name = var.name.clone().unwrap_or_default();
            let (line, column) = lint::locate_binding(original, &name);
            Some(format!(
                "error: {}:{line}:{column}: binding `{name}` (@group({}) @binding({})): {why}",
                stage.rel_path, rb.group, rb.binding
            ))
        })
        .collect()
}

/// Remove terminal colour codes (wesl colours its messages; cargo warnings and logs should not).
fn strip_ansi(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    let mut chars = s.chars();
    while let Some(c) = chars.next() {
        if c == '\u{1b}' {
            // CSI: ESC [ params letter
            for d in chars.by_ref() {
                if d.is_ascii_alphabetic() {
                    break;
                }
            }
        } else {
            out.push(c);
        }
    }
    out
}

/// `package::shared::grid` → "shaders/shared/grid.wesl" (or .wgsl), whichever exists.
fn module_file(shaders: &ShaderDir, path: &wesl::ModulePath) -> Option<String> {
    // A module of fieldkit's package (`fieldkit::seed`) is a file of the fieldkit-wesl crate,
    // named by its absolute path; another package's is not a file of this folder.
    if let wgsl_parse::syntax::PathOrigin::Package(name) = &path.origin {
        if name.as_str() != fieldkit_wesl::PACKAGE.root.name {
            return None;
        }
        let comps: Vec<String> = path.components.iter().map(|c| c.to_string()).collect();
        return Some(format!(
            "{}/{}.wesl",
            fieldkit_wesl::SOURCE_DIR,
            comps.join("/")
        ));
    }
    let comps: Vec<String> = path.components.iter().map(|c| c.to_string()).collect();
    let rel = comps.join("/");
    for ext in ["wesl", "wgsl"] {
        let p = shaders.root().join(format!("{rel}.{ext}"));
        if p.exists() {
            return Some(format!("{}/{rel}.{ext}", shaders.dir));
        }
    }
    None
}

/// A span in the linked text, mapped back to a file: exact where the erroneous text appears in
/// the original declaration, else the declaration's start.
struct Mapped {
    file: String,
    range: std::ops::Range<usize>,
}

fn map_span(linked: &Linked, crate_root: &Path, span: std::ops::Range<usize>) -> Option<Mapped> {
    let origin = linked
        .origins
        .iter()
        .find(|o| o.linked.start <= span.start && span.start <= o.linked.end)?;
    let (file, decl_range) = origin.file.clone()?;
    let original = std::fs::read_to_string(crate_root.join(&file)).ok()?;
    let decl_text = original.get(decl_range.clone())?;
    let needle = linked.text.get(span.clone()).unwrap_or("");
    // The printer normalises whitespace, so search with whitespace removed on both sides.
    let squash = |s: &str| -> (String, Vec<usize>) {
        let mut out = String::new();
        let mut idx = Vec::new();
        for (i, c) in s.char_indices() {
            if !c.is_whitespace() {
                out.push(c);
                idx.push(i);
            }
        }
        (out, idx)
    };
    let (hay, hay_idx) = squash(decl_text);
    let (pat, _) = squash(needle);
    // Several occurrences: pick the one whose relative position in the declaration is closest.
    let rel = span.start - origin.linked.start;
    let mut best: Option<(usize, usize)> = None;
    if !pat.is_empty() {
        for (pos, _) in hay.match_indices(&pat) {
            let start = hay_idx[pos];
            let end = hay_idx[pos + pat.len() - 1] + 1;
            let score = start.abs_diff(rel);
            if best.is_none_or(|(s, _)| score < s.abs_diff(rel)) {
                best = Some((start, end));
            }
        }
    }
    let (s, e) = best.unwrap_or((0, decl_text.find('\n').unwrap_or(decl_text.len())));
    Some(Mapped {
        file,
        range: decl_range.start + s..decl_range.start + e,
    })
}

/// Render a naga error against the original files, in naga's own annotated style.
fn render(
    crate_root: &Path,
    linked: &Linked,
    stage: &StageFile,
    message: &str,
    labels: &[(std::ops::Range<usize>, String)],
    notes: Vec<String>,
) -> String {
    let mut files = SimpleFiles::new();
    let mut ids = std::collections::BTreeMap::new();
    let mut diag_labels = Vec::new();
    for (range, text) in labels {
        let Some(m) = map_span(linked, crate_root, range.clone()) else {
            continue;
        };
        let id = *ids.entry(m.file.clone()).or_insert_with(|| {
            let src = std::fs::read_to_string(crate_root.join(&m.file)).unwrap_or_default();
            files.add(m.file.clone(), src)
        });
        let label = if diag_labels.is_empty() {
            Label::primary(id, m.range)
        } else {
            Label::secondary(id, m.range)
        };
        diag_labels.push(label.with_message(text.clone()));
    }
    let mut notes = notes;
    if diag_labels.is_empty() {
        // No span could be mapped: show the place in the linked text instead of nothing.
        let id = files.add(format!("{} (linked)", stage.rel_path), linked.text.clone());
        for (range, text) in labels {
            diag_labels.push(Label::primary(id, range.clone()).with_message(text.clone()));
        }
        notes.push(format!("in stage {}", stage.id()));
    }
    let diagnostic = Diagnostic::error()
        .with_message(message)
        .with_labels(diag_labels)
        .with_notes(notes);
    let mut writer = term::termcolor::NoColor::new(Vec::new());
    let config = term::Config::default();
    if term::emit_to_write_style(&mut writer, &config, &files, &diagnostic).is_err() {
        return format!("error: {message} ({})", stage.rel_path);
    }
    String::from_utf8_lossy(&writer.into_inner()).into_owned()
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
    // A vertex input the generated vertex struct cannot hold would shift every attribute after
    // it: an error at the entry point, not a silent gap.
    let mut unmapped = Vec::new();
    for ep in module
        .entry_points
        .iter()
        .filter(|e| e.stage == naga::ShaderStage::Vertex)
    {
        for (location, name, ty) in reflect::located_args(&module, &ep.function) {
            if reflect::vertex_format(&module, ty).is_none() {
                let (line, column) = lint::locate(&original, &format!("fn {}", ep.name));
                unmapped.push(format!(
                    "error: {}:{line}:{column}: vertex input `{name}` (@location({location})) of `{}` is `{}`, which has no vertex format fieldkit's generated vertex structs hold (32-bit scalars and vectors: f32, u32, i32)",
                    stage.rel_path,
                    ep.name,
                    reflect::wgsl_type(&module, ty)
                ));
            }
        }
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
    Ok(Stage {
        file: stage.clone(),
        source: linked.text,
        module,
        info,
        original,
        features,
        dynamic_offsets: Vec::new(),
        shared: linked.shared,
    })
}

/// The naga capabilities wgpu grants for a device feature, as `wgpu-naga-bridge` maps them,
/// with the `wgpu::Features` constants each needs.
const FEATURE_CAPABILITIES: &[(naga::valid::Capabilities, &[&str])] = {
    use naga::valid::Capabilities as C;
    &[
        (C::IMMEDIATES, &["IMMEDIATES"]),
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
/// with binding arrays or immediates, each capability of [`FEATURE_CAPABILITIES`] whose
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
    if arrays.is_empty() && !immediates {
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
mod tests {
    use super::*;

    /// A throwaway crate root with a shared helper and the given stage files.
    fn tree(stages: &[(&str, &str)]) -> PathBuf {
        let n = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap()
            .as_nanos();
        let root =
            std::env::temp_dir().join(format!("fieldkit-toolchain-{}-{n}", std::process::id()));
        std::fs::create_dir_all(root.join("shaders/shared")).unwrap();
        std::fs::create_dir_all(root.join("shaders/room")).unwrap();
        std::fs::write(root.join("shaders/shared/util.wesl"), "// Helpers.\n\nfn twice(x: u32) -> u32 {\n    return x * 2u;\n}\n\nfn broken_helper() -> f32 {\n    return 1u;\n}\n").unwrap();
        for (name, src) in stages {
            std::fs::write(root.join(format!("shaders/room/{name}.wgsl")), src).unwrap();
        }
        root
    }

    /// A density march links the module's `density` into the template and generates its three
    /// entry points; a bad name, a clash with a stage file and a density of the wrong type are
    /// errors that say which.
    #[test]
    fn density_marches_link_the_users_function() {
        let root = tree(&[]);
        std::fs::write(
            root.join("shaders/shared/fog.wesl"),
            "// A fog.\nfn density(p: vec3<f32>) -> f32 {\n    return exp(-p.y);\n}\n",
        )
        .unwrap();
        std::fs::write(
            root.join("shaders/shared/wrong.wesl"),
            "// Not a density.\nfn density(p: vec3<f32>) -> vec2<f32> {\n    return p.xy;\n}\n",
        )
        .unwrap();
        // The template's own helper module is broken on purpose in `tree`: unused, unlinked.
        let out = root.join("shaders.rs");
        Builder::new("shaders")
            .deny_lints()
            .density_march("room::fog_march", "shared::fog")
            .build_to(&root, &out)
            .expect("builds");
        let code = std::fs::read_to_string(&out).unwrap();
        for entry in [
            "pub mod march",
            "pub mod bricks",
            "pub mod bake",
            "fog_density",
        ] {
            assert!(code.contains(entry), "{entry} missing");
        }
        let err = |stage: &str, module: &str| {
            Builder::new("shaders")
                .density_march(stage, module)
                .build_to(&root, &out)
                .unwrap_err()
                .join("\n")
        };
        assert!(err("fog_march", "shared::fog").contains("name the stage room::name"));
        assert!(err("shared::fog_march", "shared::fog").contains("name the stage room::name"));
        assert!(err("room::fog_march", "shared/fog").contains("name the density module"));
        std::fs::write(
            root.join("shaders/room/taken.wgsl"),
            "// Taken.\n@compute @workgroup_size(1)\nfn main() {}\n",
        )
        .unwrap();
        assert!(err("room::taken", "shared::fog").contains("already a stage file"));
        let wrong = err("room::wrong_march", "shared::wrong");
        assert!(
            wrong.contains("density march `room::wrong_march` over the module `shared::wrong`"),
            "{wrong}"
        );
        let missing = err("room::none_march", "shared::nothing");
        assert!(missing.contains("none_march"), "{missing}");
    }

    /// One build writes one file: the linked WGSL of a stage importing from two packages (the
    /// crate's own `shared::fog` and `fieldkit::…`, whose modules WESL appends in hash-map
    /// order) is the same on every build — CI once rebuilt a snapshotted file in the other
    /// order. Hash-map seeds change per map, so a dozen builds in one process see both orders.
    #[test]
    fn linking_is_deterministic() {
        let root = tree(&[]);
        std::fs::write(
            root.join("shaders/shared/fog.wesl"),
            "// A fog.\nfn density(p: vec3<f32>) -> f32 {\n    return exp(-p.y);\n}\n",
        )
        .unwrap();
        let out = root.join("shaders.rs");
        let build = || {
            Builder::new("shaders")
                .density_march("room::fog_march", "shared::fog")
                .build_to(&root, &out)
                .expect("builds");
            std::fs::read_to_string(&out).unwrap()
        };
        let first = build();
        for run in 1..12 {
            assert!(
                build() == first,
                "build {run} wrote another file than build 0"
            );
        }
    }

    /// `Builder` writes bindings that reach fieldkit's runtime through the path asked for, and
    /// leaves an unchanged file untouched; a broken stage is an error at its file:line:col.
    #[test]
    fn builder_writes_bindings_for_a_user_crate() {
        let root = tree(&[(
            "double",
            "// Doubles each value.\nimport package::shared::util::twice;\n@group(0) @binding(0) var<storage, read_write> v: array<u32>;\n@compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    v[id.x] = twice(v[id.x]);\n}\n",
        )]);
        let out = root.join("shaders.rs");
        Builder::new("shaders")
            .build_to(&root, &out)
            .expect("builds");
        let code = std::fs::read_to_string(&out).unwrap();
        assert!(
            code.starts_with("// @generated by fieldkit-build"),
            "{code}"
        );
        assert!(
            code.contains("::fieldkit::bind::StorageReadWrite"),
            "{code}"
        );
        assert!(!code.contains("crate::bind"), "{code}");
        let before = std::fs::metadata(&out).unwrap().modified().unwrap();
        std::thread::sleep(std::time::Duration::from_millis(20));
        Builder::new("shaders").build_to(&root, &out).unwrap();
        assert_eq!(std::fs::metadata(&out).unwrap().modified().unwrap(), before);
        // A stage without its header comment: a lint finding, an error only when denied.
        std::fs::write(
            root.join("shaders/room/bare.wgsl"),
            "@group(0) @binding(0) var<storage, read_write> w: array<u32>;\n@compute @workgroup_size(1)\nfn main() {\n    w[0] = 1u;\n}\n",
        )
        .unwrap();
        Builder::new("shaders")
            .build_to(&root, &out)
            .expect("lints warn by default");
        let errors = Builder::new("shaders")
            .deny_lints()
            .build_to(&root, &out)
            .unwrap_err();
        assert!(
            errors.len() == 1
                && errors[0].starts_with("shaders/room/bare.wgsl:1:1: [header-comment]"),
            "{errors:#?}"
        );
        std::fs::remove_file(root.join("shaders/room/bare.wgsl")).unwrap();
        // A dynamic offset on a named buffer binding; names that match none are errors.
        Builder::new("shaders")
            .dynamic_offset("room::double::v")
            .build_to(&root, &out)
            .expect("builds");
        assert!(
            std::fs::read_to_string(&out)
                .unwrap()
                .contains("has_dynamic_offset: true")
        );
        let errors = Builder::new("shaders")
            .dynamic_offset("room::nope::v")
            .dynamic_offset("room::double::missing")
            .build_to(&root, &out)
            .unwrap_err();
        assert!(
            errors.len() == 2
                && errors[0].contains("no stage `room::nope`")
                && errors[1].contains("no uniform or storage buffer binding `missing`"),
            "{errors:#?}"
        );
        let own = Builder::new("shaders").runtime("crate");
        own.build_to(&root, &out).unwrap();
        assert!(
            std::fs::read_to_string(&out)
                .unwrap()
                .contains("crate::bind::StorageReadWrite")
        );
        std::fs::write(
            root.join("shaders/room/double.wgsl"),
            "// Broken.\n@compute @workgroup_size(64)\nfn main() {\n    let x: f32 = 1u;\n}\n",
        )
        .unwrap();
        let errors = Builder::new("shaders").build_to(&root, &out).unwrap_err();
        assert!(
            errors[0].contains("shaders/room/double.wgsl:4:"),
            "{errors:#?}"
        );
        std::fs::remove_dir_all(&root).unwrap();
    }

    /// Bindings the generated code cannot hold are build errors at their declaration, not
    /// silently left out (an unsized binding array, an external texture); a file that imports
    /// nothing reaches naga even where the pinned WESL parser refuses it (`binding_array`).
    #[test]
    fn unsupported_bindings_are_errors_naming_the_binding() {
        let root = tree(&[
            (
                "a_array",
                "// Binding array without a length, no imports.\nenable wgpu_binding_array;\n@group(0) @binding(0) var textures: binding_array<texture_2d<f32>>;\n@group(0) @binding(1) var<storage, read_write> out: array<f32>;\n@compute @workgroup_size(1)\nfn main() {\n    out[0] = textureLoad(textures[0], vec2<i32>(0, 0), 0).x;\n}\n",
            ),
            (
                "b_external",
                "// External texture.\n@group(0) @binding(0) var<storage, read_write> out: array<f32>;\n@group(0) @binding(1) var video: texture_external;\n@compute @workgroup_size(1)\nfn main() {\n    out[0] = textureLoad(video, vec2<u32>(0u, 0u)).x;\n}\n",
            ),
            (
                "c_fine",
                "// A valid stage.\n@compute @workgroup_size(1)\nfn main() {}\n",
            ),
        ]);
        let errors = build_all(&root).err().expect("unsupported bindings fail");
        assert_eq!(errors.len(), 2, "{errors:#?}");
        assert!(
            errors[0].contains("shaders/room/a_array.wgsl:3:")
                && errors[0].contains("binding `textures` (@group(0) @binding(0))")
                && errors[0].contains("needs a length"),
            "{}",
            errors[0]
        );
        assert!(
            errors[1].contains("shaders/room/b_external.wgsl:3:")
                && errors[1].contains("binding `video` (@group(0) @binding(1))")
                && errors[1].contains("external textures"),
            "{}",
            errors[1]
        );
        std::fs::remove_dir_all(&root).ok();
    }

    /// With `check_portability`, a stage that does not translate to a backend language is a
    /// `[portability]` finding (here naga's HLSL writer panics on a binding array of buffers):
    /// a warning, or an error with `deny_lints`.
    #[cfg(feature = "portability")]
    #[test]
    fn portability_findings_come_from_the_build() {
        let root = tree(&[(
            "blocks",
            "// A binding array of storage buffers.\nenable wgpu_binding_array;\nstruct Block {\n    values: array<u32>,\n}\n@group(0) @binding(0) var<storage, read_write> blocks: binding_array<Block, 2>;\n@compute @workgroup_size(1)\nfn main() {\n    blocks[1].values[0] = blocks[0].values[0];\n}\n",
        )]);
        let out = root.join("shaders.rs");
        Builder::new("shaders")
            .check_portability()
            .build_to(&root, &out)
            .expect("portability findings warn by default");
        let errors = Builder::new("shaders")
            .check_portability()
            .deny_lints()
            .build_to(&root, &out)
            .unwrap_err();
        assert!(
            errors.iter().any(|e| e.starts_with(
                "shaders/room/blocks.wgsl:1:1: [portability] cannot translate to HLSL"
            )),
            "{errors:#?}"
        );
        std::fs::remove_dir_all(&root).ok();
    }

    /// A vertex input the generated vertex struct cannot hold (f16) is a build error naming it,
    /// not an attribute silently left out of the struct and its stride.
    #[test]
    fn unmapped_vertex_inputs_are_errors() {
        let root = tree(&[(
            "half",
            "// Half-float vertex input.\nenable f16;\n@vertex\nfn vs(@location(0) p: vec3<f32>, @location(1) h: vec2<f16>) -> @builtin(position) vec4<f32> {\n    return vec4<f32>(p + vec3<f32>(vec2<f32>(h), 0.0), 1.0);\n}\n",
        )]);
        let errors = build_all(&root).err().expect("an f16 vertex input fails");
        assert!(
            errors.len() == 1
                && errors[0].contains("shaders/room/half.wgsl:4:")
                && errors[0].contains("vertex input `h` (@location(1))")
                && errors[0].contains("vec2<f16>"),
            "{errors:#?}"
        );
        std::fs::remove_dir_all(&root).ok();
    }

    /// Binding arrays (sampled and storage textures, samplers, storage buffers), in a file that
    /// imports (WESL links it though its parser reserves the word), reach the
    /// generated code with their counts and array resource types, and the features they need
    /// are found by validation: non-uniform indexing only where an index is non-uniform; an
    /// immediate block gives its size and `IMMEDIATES`.
    #[test]
    fn binding_arrays_and_immediates_are_bound_with_the_features_they_need() {
        let root = tree(&[
            (
                "a_arrays",
                "// Binding arrays, indexed by constants and by a non-uniform value, in a file that imports.\nimport package::shared::util::twice;\nenable wgpu_binding_array;\nstruct Block {\n    values: array<u32>,\n}\n@group(0) @binding(0) var textures: binding_array<texture_2d<f32>, 4>;\n@group(0) @binding(1) var samplers: binding_array<sampler, 2>;\n@group(0) @binding(2) var<storage, read_write> blocks: binding_array<Block, 3>;\n@group(0) @binding(3) var<storage, read_write> out: array<f32>;\n@compute @workgroup_size(8)\nfn main(@builtin(local_invocation_index) i: u32) {\n    let t = textureSampleLevel(textures[i % 4u], samplers[1], vec2<f32>(0.5), 0.0).x;\n    out[i] = t + f32(twice(blocks[2].values[i]));\n}\n",
            ),
            (
                "b_immediates",
                "// Immediates.\nstruct Push {\n    scale: f32,\n    offset: vec2<f32>,\n}\nvar<immediate> push: Push;\n@group(0) @binding(0) var<storage, read_write> out: array<f32>;\n@compute @workgroup_size(8)\nfn main(@builtin(local_invocation_index) i: u32) {\n    out[i] = push.scale * f32(i) + push.offset.x;\n}\n",
            ),
        ]);
        let out = root.join("shaders.rs");
        let code = Builder::new("shaders")
            .build_to(&root, &out)
            .map(|p| std::fs::read_to_string(p).unwrap())
            .unwrap_or_else(|e| panic!("{e:#?}"));
        for want in [
            "pub textures: ::fieldkit::bind::Textures<'a>",
            "pub samplers: ::fieldkit::bind::Samplers<'a>",
            "pub blocks: ::fieldkit::bind::Buffers<'a, Block>",
            "count: core::num::NonZeroU32::new(4)",
            "count: core::num::NonZeroU32::new(3)",
            "wgpu::Features::TEXTURE_BINDING_ARRAY",
            "wgpu::Features::STORAGE_RESOURCE_BINDING_ARRAY",
            "wgpu::Features::SAMPLED_TEXTURE_AND_STORAGE_BUFFER_ARRAY_NON_UNIFORM_INDEXING",
            "pub const IMMEDIATE_SIZE: u32 = 16;",
            "wgpu::Features::IMMEDIATES",
            "immediate_size: 16",
            "pub struct Push",
        ] {
            assert!(code.contains(want), "missing {want:?} in\n{code}");
        }
        // Only the textures are indexed non-uniformly (the samplers and buffers by constants),
        // and no storage texture is bound.
        let arrays = &code
            [code.find("pub mod a_arrays").unwrap()..code.find("pub mod b_immediates").unwrap()];
        assert!(
            !arrays.contains("wgpu::Features::STORAGE_TEXTURE_ARRAY_NON_UNIFORM_INDEXING")
                && !arrays.contains("wgpu::Features::IMMEDIATES"),
            "{arrays}"
        );
        std::fs::remove_dir_all(&root).ok();
    }

    /// fieldkit's helpers are a package every link has (`import fieldkit::…`), beside the
    /// folder's own; a module the package lacks is an error naming it, at the stage's file.
    #[test]
    fn stages_import_fieldkits_package() {
        let root = tree(&[
            (
                "a_seeds",
                "// Packs seeds with fieldkit's helper.\nimport fieldkit::seed::{NO_SEED, pack_seed2};\nimport package::shared::util::twice;\n@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n@compute @workgroup_size(64)\nfn main(@builtin(global_invocation_id) id: vec3<u32>) {\n    out[id.x] = select(NO_SEED, pack_seed2(vec2<u32>(id.x, twice(id.x))), id.x > 0u);\n}\n",
            ),
            (
                "b_missing",
                "// Imports a module the package does not have.\nimport fieldkit::nowhere::thing;\n@compute @workgroup_size(1)\nfn main() { _ = thing(); }\n",
            ),
        ]);
        let errors = build_all(&root).err().expect("the missing module fails");
        assert_eq!(errors.len(), 1, "{errors:#?}");
        assert!(
            errors[0].contains("shaders/room/b_missing.wgsl") && errors[0].contains("nowhere"),
            "{}",
            errors[0]
        );
        std::fs::remove_file(root.join("shaders/room/b_missing.wgsl")).unwrap();
        let stages = build_all(&root).expect("the package import links");
        let linked = &stages[0].source;
        // The helper's body came from fieldkit's seed.wesl (the 16/16 packing).
        assert!(linked.contains("<< 16u"), "{linked}");
        // A struct imported from the package is named as in the package, as one imported from
        // the folder's own helpers is.
        std::fs::write(
            root.join("shaders/room/c_waves.wgsl"),
            "// Reads waves in fieldkit's layout.\nimport fieldkit::gerstner::GerstnerWave;\n@group(0) @binding(0) var<uniform> wave: GerstnerWave;\n@group(0) @binding(1) var<storage, read_write> out: array<f32>;\n@compute @workgroup_size(1)\nfn main() {\n    out[0] = wave.amplitude;\n}\n",
        )
        .unwrap();
        let out = root.join("shaders.rs");
        Builder::new("shaders")
            .build_to(&root, &out)
            .expect("builds");
        let code = std::fs::read_to_string(&out).unwrap();
        assert!(code.contains("pub struct GerstnerWave"), "{code}");
        std::fs::remove_dir_all(root).ok();
    }

    #[test]
    fn every_broken_stage_is_reported_at_its_original_line_and_column() {
        let root = tree(&[
            // Type error in the stage itself, on line 6, after an import that shifts linked text.
            (
                "a_type",
                "// Stage with a type error.\nimport package::shared::util::twice;\n@group(0) @binding(0) var<storage, read_write> out: array<u32>;\n@compute @workgroup_size(1)\nfn main() {\n    out[0] = twice(1.5);\n}\n",
            ),
            // Parse error on line 3.
            (
                "b_parse",
                "// Stage with a syntax error.\n@compute @workgroup_size(1)\nfn main() { let x = ; }\n",
            ),
            (
                "c_fine",
                "// A valid stage.\n@compute @workgroup_size(1)\nfn main() {}\n",
            ),
            // Error inside an imported helper: reported in the helper's file.
            (
                "d_helper",
                "// Uses a broken helper.\nimport package::shared::util::broken_helper;\n@compute @workgroup_size(1)\nfn main() { _ = broken_helper(); }\n",
            ),
        ]);
        let errors = build_all(&root).err().expect("broken stages fail");
        assert_eq!(errors.len(), 3, "{errors:#?}");
        assert!(
            errors[0].contains("shaders/room/a_type.wgsl:6:"),
            "{}",
            errors[0]
        );
        assert!(
            errors[1].contains("shaders/room/b_parse.wgsl:3:"),
            "{}",
            errors[1]
        );
        assert!(
            errors[2].contains("shaders/shared/util.wesl:7:1")
                && errors[2].contains("8 │     return 1u;"),
            "{}",
            errors[2]
        );
        eprintln!("{}", errors.join("\n"));
        std::fs::remove_dir_all(root).ok();
    }
}
