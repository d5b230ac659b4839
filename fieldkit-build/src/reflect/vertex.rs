//! Vertex inputs as the buffers hold them: each input's vertex format and step mode, by default
//! 32-bit and per vertex (per instance for an `instance_` name), or as the line that declares
//! the input says in a comment:
//!
//! ```wgsl
//! struct VertexIn {
//!     @location(0) position: vec3<f32>,
//!     @location(1) color: vec4<f32>,  // vertex: unorm8x4
//!     @location(2) normal: vec4<f32>, // vertex: snorm16x4
//!     @location(3) offset: vec2<f32>, // vertex: float16x2, instance
//! }
//! ```
//!
//! The format is a WebGPU vertex format name (`unorm8x4`, `sint16x2`, `float16x4`,
//! `unorm10-10-10-2`, …) whose scalar kind is the input's (float formats feed `f32`/`f16`
//! inputs, `uint` formats `u32`, `sint` formats `i32`); the step is `vertex` or `instance`.
//! The comment goes on the line declaring the input, inside the vertex entry's parameter list or
//! its input struct.

use naga::{ScalarKind, TypeInner};

use super::VertexInput;

/// One WebGPU vertex format: its WGSL-side name, `wgpu::VertexFormat` variant, the scalar kind
/// it feeds, its host element type and count, and its bytes.
type Format = (
    &'static str,
    &'static str,
    ScalarKind,
    &'static str,
    u32,
    u32,
);

use ScalarKind::{Float, Sint, Uint};

/// Every vertex format wgpu offers without a feature (64-bit floats need one and are left out).
const FORMATS: &[Format] = &[
    ("uint8", "Uint8", Uint, "u8", 1, 1),
    ("uint8x2", "Uint8x2", Uint, "u8", 2, 2),
    ("uint8x4", "Uint8x4", Uint, "u8", 4, 4),
    ("sint8", "Sint8", Sint, "i8", 1, 1),
    ("sint8x2", "Sint8x2", Sint, "i8", 2, 2),
    ("sint8x4", "Sint8x4", Sint, "i8", 4, 4),
    ("unorm8", "Unorm8", Float, "u8", 1, 1),
    ("unorm8x2", "Unorm8x2", Float, "u8", 2, 2),
    ("unorm8x4", "Unorm8x4", Float, "u8", 4, 4),
    ("unorm8x4-bgra", "Unorm8x4Bgra", Float, "u8", 4, 4),
    ("snorm8", "Snorm8", Float, "i8", 1, 1),
    ("snorm8x2", "Snorm8x2", Float, "i8", 2, 2),
    ("snorm8x4", "Snorm8x4", Float, "i8", 4, 4),
    ("uint16", "Uint16", Uint, "u16", 1, 2),
    ("uint16x2", "Uint16x2", Uint, "u16", 2, 4),
    ("uint16x4", "Uint16x4", Uint, "u16", 4, 8),
    ("sint16", "Sint16", Sint, "i16", 1, 2),
    ("sint16x2", "Sint16x2", Sint, "i16", 2, 4),
    ("sint16x4", "Sint16x4", Sint, "i16", 4, 8),
    ("unorm16", "Unorm16", Float, "u16", 1, 2),
    ("unorm16x2", "Unorm16x2", Float, "u16", 2, 4),
    ("unorm16x4", "Unorm16x4", Float, "u16", 4, 8),
    ("snorm16", "Snorm16", Float, "i16", 1, 2),
    ("snorm16x2", "Snorm16x2", Float, "i16", 2, 4),
    ("snorm16x4", "Snorm16x4", Float, "i16", 4, 8),
    // Half floats travel as their bits (`half::f16::to_bits`).
    ("float16", "Float16", Float, "u16", 1, 2),
    ("float16x2", "Float16x2", Float, "u16", 2, 4),
    ("float16x4", "Float16x4", Float, "u16", 4, 8),
    ("float32", "Float32", Float, "f32", 1, 4),
    ("float32x2", "Float32x2", Float, "f32", 2, 8),
    ("float32x3", "Float32x3", Float, "f32", 3, 12),
    ("float32x4", "Float32x4", Float, "f32", 4, 16),
    ("uint32", "Uint32", Uint, "u32", 1, 4),
    ("uint32x2", "Uint32x2", Uint, "u32", 2, 8),
    ("uint32x3", "Uint32x3", Uint, "u32", 3, 12),
    ("uint32x4", "Uint32x4", Uint, "u32", 4, 16),
    ("sint32", "Sint32", Sint, "i32", 1, 4),
    ("sint32x2", "Sint32x2", Sint, "i32", 2, 8),
    ("sint32x3", "Sint32x3", Sint, "i32", 3, 12),
    ("sint32x4", "Sint32x4", Sint, "i32", 4, 16),
    // Three 10-bit channels and a 2-bit one, packed in one `u32`.
    ("unorm10-10-10-2", "Unorm10_10_10_2", Float, "u32", 1, 4),
];

/// The host field's type of a format: its element, or an array of them.
fn rust_of(f: &Format) -> String {
    let (_, _, _, host, count, _) = *f;
    if count == 1 {
        host.to_string()
    } else {
        format!("[{host}; {count}]")
    }
}

/// The marker of a declaration comment.
const MARKER: &str = "// vertex:";

/// A problem with a vertex entry's inputs: 1-based line and column in the stage file, and what.
pub(crate) type Problem = (usize, usize, String);

/// The vertex entry `ep`'s inputs with their formats and steps (by location), or every problem
/// found: an input whose type no format feeds, a declaration naming an unknown word or a format
/// of another scalar kind, a declaration on a line that declares no input.
pub(crate) fn inputs(
    original: &str,
    module: &naga::Module,
    ep: &naga::EntryPoint,
) -> Result<Vec<VertexInput>, Vec<Problem>> {
    let lines: Vec<&str> = original.lines().collect();
    let regions = input_regions(&lines, module, ep);
    let mut claimed = Vec::new();
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for (location, name, ty) in super::located_args(module, &ep.function) {
        let line = regions
            .iter()
            .flat_map(|r| r.clone())
            .find(|&i| declares(code_of(lines[i]), &name));
        let declared = line.and_then(|i| {
            let at = lines[i].find(MARKER)?;
            claimed.push(i);
            Some((i, at, &lines[i][at + MARKER.len()..]))
        });
        let wgsl = super::wgsl_type(module, ty);
        let mut problem = |i: usize, at: usize, message: String| {
            problems.push((i + 1, at + 1, message));
        };
        let mut format = None;
        let mut instance = name.starts_with("instance_");
        if let Some((i, at, words)) = declared {
            for word in words.split(',').map(str::trim).filter(|w| !w.is_empty()) {
                match word {
                    "vertex" => instance = false,
                    "instance" => instance = true,
                    _ => match FORMATS.iter().find(|f| f.0 == word) {
                        Some(f) if format.is_none() => format = Some(f),
                        Some(_) => problem(i, at, format!("`{name}` declares two formats")),
                        None => problem(
                            i,
                            at,
                            format!(
                                "`{word}` is not a vertex format or step (formats: {}; steps: vertex, instance)",
                                FORMATS.iter().map(|f| f.0).collect::<Vec<_>>().join(", ")
                            ),
                        ),
                    },
                }
            }
        }
        let Some((kind, n)) = scalar_and_count(module, ty) else {
            let (i, at) = line.map_or_else(|| entry_at(&lines, &ep.name), |i| (i, 0));
            problem(
                i,
                at,
                format!(
                    "vertex input `{name}` (@location({location})) of `{}` is `{wgsl}`: a vertex input is a scalar or vector",
                    ep.name
                ),
            );
            continue;
        };
        let format = match format {
            Some(f) if f.2 == kind => f,
            Some(f) => {
                let (i, at, _) = declared.expect("a format was declared");
                problem(
                    i,
                    at,
                    format!(
                        "`{name}` is `{wgsl}`, but `{}` feeds {} inputs",
                        f.0,
                        kind_name(f.2)
                    ),
                );
                continue;
            }
            None => match default_format(kind, n, module, ty) {
                Some(f) => f,
                None => {
                    let (i, at) = line.map_or_else(|| entry_at(&lines, &ep.name), |i| (i, 0));
                    problem(
                        i,
                        at,
                        format!(
                            "vertex input `{name}` (@location({location})) of `{}` is `{wgsl}`, which no 32-bit format feeds: declare its format on its line, as `// vertex: float16x{n}`",
                            ep.name
                        ),
                    );
                    continue;
                }
            },
        };
        out.push(VertexInput {
            location,
            name,
            ty: wgsl,
            format: format.1.to_string(),
            rust: rust_of(format),
            size: format.5,
            instance,
        });
    }
    for r in &regions {
        for i in r.clone() {
            if let Some(at) = lines[i].find(MARKER).filter(|_| !claimed.contains(&i)) {
                problems.push((
                    i + 1,
                    at + 1,
                    format!(
                        "a `{MARKER}` comment on a line that declares no vertex input of `{}`",
                        ep.name
                    ),
                ));
            }
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// The 32-bit format of an input's own type (`vec3<f32>` → `Float32x3`), where it has one.
fn default_format(
    kind: ScalarKind,
    n: u32,
    module: &naga::Module,
    ty: naga::Handle<naga::Type>,
) -> Option<&'static Format> {
    let width = match module.types[ty].inner {
        TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } => s.width,
        _ => return None,
    };
    (width == 4)
        .then(|| {
            FORMATS.iter().find(|f| {
                f.2 == kind && f.5 == 4 * n && f.3.ends_with("32") && !f.0.starts_with("unorm10")
            })
        })
        .flatten()
}

fn scalar_and_count(
    module: &naga::Module,
    ty: naga::Handle<naga::Type>,
) -> Option<(ScalarKind, u32)> {
    match module.types[ty].inner {
        TypeInner::Scalar(s) => Some((s.kind, 1)),
        TypeInner::Vector { size, scalar } => Some((scalar.kind, size as u32)),
        _ => None,
    }
    .filter(|(k, _)| matches!(k, Float | Uint | Sint))
}

fn kind_name(k: ScalarKind) -> &'static str {
    match k {
        Uint => "`u32`",
        Sint => "`i32`",
        _ => "`f32`/`f16`",
    }
}

/// A line's code, its comment cut off.
fn code_of(line: &str) -> &str {
    line.split("//").next().unwrap_or(line)
}

/// Whether `code` declares `name` (`name:` or `name :`, `name` a whole word).
fn declares(code: &str, name: &str) -> bool {
    let word = |c: char| c.is_alphanumeric() || c == '_';
    code.match_indices(name).any(|(at, _)| {
        let before = code[..at].chars().next_back();
        let after = code[at + name.len()..].trim_start();
        !before.is_some_and(word) && after.starts_with(':') && !after.starts_with("::")
    })
}

/// The 0-based line and column of `fn name` (0, 0 where it is not in the file).
fn entry_at(lines: &[&str], name: &str) -> (usize, usize) {
    let pat = format!("fn {name}");
    lines
        .iter()
        .enumerate()
        .find_map(|(i, l)| l.find(&pat).map(|c| (i, c)))
        .unwrap_or((0, 0))
}

/// The line ranges of the stage file that declare `ep`'s inputs: its parameter list and the
/// bodies of the structs it takes (a struct imported from another file is not in this one:
/// its inputs take their default formats).
fn input_regions(
    lines: &[&str],
    module: &naga::Module,
    ep: &naga::EntryPoint,
) -> Vec<std::ops::Range<usize>> {
    let mut out = Vec::new();
    let (start, column) = entry_at(lines, &ep.name);
    if lines
        .get(start)
        .is_some_and(|l| l.contains(&format!("fn {}", ep.name)))
    {
        out.push(start..parameters_end(lines, start, column));
    }
    for arg in &ep.function.arguments {
        if arg.binding.is_some() {
            continue;
        }
        let Some(struct_name) = module.types[arg.ty].name.as_deref() else {
            continue;
        };
        let pat = format!("struct {struct_name}");
        if let Some(i) = lines.iter().position(|l| {
            code_of(l).find(&pat).is_some_and(|at| {
                !code_of(l)[at + pat.len()..].starts_with(|c: char| c.is_alphanumeric() || c == '_')
            })
        }) {
            out.push(i..until(lines, i, '}'));
        }
    }
    out
}

/// One past the line that closes the parameter list opened after `fn` at `(line, column)`.
fn parameters_end(lines: &[&str], line: usize, column: usize) -> usize {
    let mut depth = 0;
    for (i, l) in lines.iter().enumerate().skip(line) {
        let code = code_of(l);
        let code = if i == line {
            &code[column.min(code.len())..]
        } else {
            code
        };
        for c in code.chars() {
            match c {
                '(' => depth += 1,
                ')' if depth == 1 => return i + 1,
                ')' => depth -= 1,
                _ => {}
            }
        }
    }
    lines.len()
}

/// One past the first line at or after `from` whose code holds `close`.
fn until(lines: &[&str], from: usize, close: char) -> usize {
    (from..lines.len())
        .find(|&i| code_of(lines[i]).contains(close))
        .map_or(lines.len(), |i| i + 1)
}
