//! Linking a stage: WESL resolves its imports, and every declaration of the linked text keeps
//! the file and span it came from, so naga's errors point at the original file:line:col.

use std::fmt::Write as _;
use std::path::Path;

use codespan_reporting::diagnostic::{Diagnostic, Label};
use codespan_reporting::files::SimpleFiles;
use codespan_reporting::term;

use super::{SHARED_DIR, ShaderDir, StageFile, lint};

/// Where a declaration of the linked output came from.
pub(crate) struct DeclOrigin {
    /// Byte range of the declaration in the linked text.
    linked: std::ops::Range<usize>,
    /// Original file (relative path) and the declaration's byte range in it.
    file: Option<(String, std::ops::Range<usize>)>,
}

/// Linked text plus the map back to original files.
pub(crate) struct Linked {
    pub(crate) text: String,
    pub(crate) origins: Vec<DeclOrigin>,
    /// Declarations from imported modules of the folder's `shared/`: mangled name, module
    /// (file stem under `shared/`), original name.
    pub(crate) shared: Vec<SharedDecl>,
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
pub(crate) fn link(shaders: &ShaderDir, stage: &StageFile) -> Result<Linked, String> {
    let root: wesl::ModulePath = format!("package::{}", stage.id())
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
pub(crate) fn binding_array_vars(source: &str) -> Vec<String> {
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
pub(crate) struct BindingArrays {
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
pub(crate) fn imports_anything(source: &str) -> bool {
    source.lines().any(|l| {
        l.trim_start()
            .strip_prefix("import")
            .is_some_and(|rest| rest.starts_with(char::is_whitespace))
    })
}

/// Bindings the generated host code cannot express, as errors at their declaration: binding
/// arrays without a length, external textures and acceleration structures would otherwise be
/// left out of the layouts without a word.
pub(crate) fn unsupported_bindings(
    stage: &StageFile,
    module: &naga::Module,
    original: &str,
) -> Vec<String> {
    use naga::TypeInner;
    module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let rb = var.binding.as_ref()?;
            let why = match &module.types[var.ty].inner {
                // Sized or not: an unsized array's length is given when its pipeline is made.
                TypeInner::BindingArray { base, .. } => match &module.types[*base].inner {
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
pub(crate) fn strip_ansi(s: &str) -> String {
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
pub(crate) fn module_file(shaders: &ShaderDir, path: &wesl::ModulePath) -> Option<String> {
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
pub(crate) struct Mapped {
    file: String,
    range: std::ops::Range<usize>,
}

pub(crate) fn map_span(
    linked: &Linked,
    crate_root: &Path,
    span: std::ops::Range<usize>,
) -> Option<Mapped> {
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
pub(crate) fn render(
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
