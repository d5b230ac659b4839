//! Which entry points make which pipelines: a compute entry alone; a fragment entry with every
//! vertex entry that writes what it reads, of its own file or of another file the fragment's
//! file names in a `// draw with: room::stage::vs_entry` line; a vertex entry no fragment entry
//! of its file draws with, alone (depth only). And the build errors where that cannot hold.

use super::super::Stage;
use std::borrow::Cow;

use super::super::reflect::{Binding, EntryPoint, Reflection, reflect};

/// The marker of a line naming a vertex entry of another file to draw this file's fragment
/// entries with.
pub const DRAW_WITH: &str = "// draw with:";

/// A vertex entry of another stage that a fragment file draws with: that stage's id and
/// reflection, and the entry's name.
pub struct External {
    pub stage: String,
    pub reflection: Reflection,
    pub entry: String,
}

impl External {
    fn entry_point(&self) -> &EntryPoint {
        self.reflection
            .entry_points
            .iter()
            .find(|e| e.name == self.entry)
            .expect("resolved by `externals`")
    }
}

/// One pipeline's worth of entry points: a compute entry, a vertex entry alone (depth only), or
/// a vertex entry paired with a fragment entry.
pub(super) struct PipelineDesc<'r> {
    /// Module name inside the stage module.
    pub module: String,
    /// The entries; a vertex entry of another file is a copy whose uses are named as this
    /// file names the same resources.
    pub entries: Vec<Cow<'r, EntryPoint>>,
    /// The vertex entry's stage, where it is another file's.
    pub vertex_stage: Option<&'r str>,
    /// Where the vertex entry is another file's: the fragment stage's reflection with that
    /// stage's bindings the vertex entry uses, so one pipeline binds both.
    pub merged: Option<Reflection>,
}

impl PipelineDesc<'_> {
    /// The stages ("vertex", "fragment", "compute") of the pipeline that use binding `b`.
    pub fn stages_using(&self, b: &super::super::reflect::Binding) -> Vec<&str> {
        self.entries
            .iter()
            .filter(|e| {
                // By variable too: two variables may share a slot where no entry point uses
                // both (a storage and a uniform view of the same data, one per pipeline).
                e.uses
                    .iter()
                    .any(|u| u.group == b.group && u.binding == b.binding && u.name == b.name)
            })
            .map(|e| e.stage.as_str())
            .collect()
    }

    /// The reflection the pipeline's bindings come from.
    pub fn reflection<'a>(&'a self, own: &'a Reflection) -> &'a Reflection {
        self.merged.as_ref().unwrap_or(own)
    }
}

/// The pipelines of a stage (`r`), with the vertex entries of other files it draws with.
pub(super) fn pipelines<'r>(r: &'r Reflection, externals: &'r [External]) -> Vec<PipelineDesc<'r>> {
    let mut out = Vec::new();
    let of = |stage: &str| -> Vec<&EntryPoint> {
        r.entry_points.iter().filter(|e| e.stage == stage).collect()
    };
    let (vertex, fragment) = (of("vertex"), of("fragment"));
    let candidates = vertex.len() + externals.len();
    let single = |e: &'r EntryPoint| PipelineDesc {
        module: e.name.clone(),
        entries: vec![Cow::Borrowed(e)],
        vertex_stage: None,
        merged: None,
    };
    for ep in &r.entry_points {
        match ep.stage.as_str() {
            "compute" => out.push(single(ep)),
            // A fragment entry draws with every vertex entry that writes what it reads: named
            // after itself where there is one such candidate, after both where there are
            // several.
            "fragment" => {
                let name = |v: &EntryPoint| {
                    if candidates == 1 {
                        ep.name.clone()
                    } else {
                        format!("{}_{}", v.name, ep.name)
                    }
                };
                for v in vertex.iter().filter(|v| pairs(v, ep)) {
                    out.push(PipelineDesc {
                        module: name(v),
                        entries: vec![Cow::Borrowed(*v), Cow::Borrowed(ep)],
                        vertex_stage: None,
                        merged: None,
                    });
                }
                for x in externals {
                    let v = x.entry_point();
                    if pairs(v, ep) {
                        let (v, merged) = merged(r, &x.reflection, v);
                        out.push(PipelineDesc {
                            module: name(&v),
                            entries: vec![Cow::Owned(v), Cow::Borrowed(ep)],
                            vertex_stage: Some(&x.stage),
                            merged: Some(merged),
                        });
                    }
                }
            }
            // A vertex entry no fragment entry draws with: a depth-only pipeline (a shadow or
            // depth pre-pass).
            "vertex" if !fragment.iter().any(|f| pairs(ep, f)) => out.push(single(ep)),
            _ => {}
        }
    }
    out
}

/// Whether `a` and `b` bind the same kind of resource of the same type (the same resource where
/// two files declare it on one slot, whatever each names it).
fn same_resource(a: &Binding, b: &Binding) -> bool {
    (a.group, a.binding) == (b.group, b.binding) && a.kind == b.kind && a.ty == b.ty
}

/// Vertex entry `v` of `other` with its uses named as `own` names the same resources, and
/// `own` with the bindings of `other` that `v` uses and `own` lacks (their struct types reached
/// in `other`'s generated module), and the features of both.
fn merged(own: &Reflection, other: &Reflection, v: &EntryPoint) -> (EntryPoint, Reflection) {
    use super::super::reflect::BindingKind;
    let mut r = own.clone();
    let mut v = v.clone();
    let path = format!(
        "{}{}::",
        "super::".repeat(1 + own.stage.split("::").count()),
        other.stage
    );
    for u in &mut v.uses {
        let Some(b) = other.bindings.iter().find(|b| {
            (b.group, b.binding, b.name.as_str()) == (u.group, u.binding, u.name.as_str())
        }) else {
            continue;
        };
        if let Some(o) = own.bindings.iter().find(|o| same_resource(o, b)) {
            u.name = o.name.clone();
            continue;
        }
        let mut b = b.clone();
        // A name the fragment's file gives another resource: `vertex_<name>` in `Resources`.
        // (On the same slot it is the same name for another type: an error, below.)
        while r
            .bindings
            .iter()
            .any(|o| o.name == b.name && (o.group, o.binding) != (b.group, b.binding))
        {
            b.name = format!("vertex_{}", b.name);
        }
        u.name = b.name.clone();
        let qualified = super::groups::qualify(other, super::groups::rust_of(&b.kind), &path);
        if let BindingKind::Uniform { rust, .. } | BindingKind::Storage { rust, .. } = &mut b.kind {
            *rust = qualified;
        }
        r.bindings.push(b);
    }
    r.bindings.sort_by_key(|b| (b.group, b.binding));
    r.features.extend(other.features.iter().cloned());
    r.features.sort();
    r.features.dedup();
    (v, r)
}

/// Whether vertex entry `v` writes every `@location` fragment entry `f` reads.
fn pairs(v: &EntryPoint, f: &EntryPoint) -> bool {
    f.stage_io.iter().all(|l| v.stage_io.contains(l))
}

/// The `// draw with:` lines of a stage file (the marker first on its line): 1-based line and column, and the named entry.
pub fn declared(original: &str) -> Vec<(usize, usize, String)> {
    original
        .lines()
        .enumerate()
        .filter_map(|(i, l)| {
            // A line of its own, so prose that quotes the marker is not one.
            let rest = l.trim_start().strip_prefix(DRAW_WITH)?;
            let at = l.len() - l.trim_start().len();
            Some((i + 1, at + 1, rest.trim().to_string()))
        })
        .collect()
}

/// The vertex entries of other stages that `stage` declares it draws with, or an error at each
/// declaration that names no vertex entry of a stage of the folder (1-based line, column,
/// message).
pub fn externals(
    stage: &Stage,
    stages: &[Stage],
) -> Result<Vec<External>, Vec<(usize, usize, String)>> {
    let mut out = Vec::new();
    let mut problems = Vec::new();
    for (line, column, named) in declared(&stage.original) {
        let Some((id, entry)) = named.rsplit_once("::") else {
            problems.push((
                line,
                column,
                format!("`{DRAW_WITH} {named}`: name a vertex entry as `room::stage::entry`"),
            ));
            continue;
        };
        let Some(other) = stages.iter().find(|s| s.file.id() == id) else {
            let ids: Vec<String> = stages.iter().map(|s| s.file.id()).collect();
            problems.push((
                line,
                column,
                format!(
                    "`{DRAW_WITH} {named}`: no stage `{id}` among those that built ({})",
                    ids.join(", ")
                ),
            ));
            continue;
        };
        let reflection = reflect(other);
        let why = match reflection.entry_points.iter().find(|e| e.name == entry) {
            None => Some(format!("`{id}` has no entry point `{entry}`")),
            Some(e) if e.stage != "vertex" => Some(format!(
                "`{id}::{entry}` is a {} entry, not a vertex entry",
                e.stage
            )),
            Some(e) if e.uses_immediate => Some(format!(
                "`{id}::{entry}` uses immediates, which a pipeline of two files cannot hold yet"
            )),
            Some(_)
                if stage
                    .module
                    .entry_points
                    .iter()
                    .any(|e| e.name == entry && e.stage == naga::ShaderStage::Vertex) =>
            {
                Some(format!(
                    "this file has a vertex entry `{entry}` too: the pipelines would share a name"
                ))
            }
            Some(_) => None,
        };
        match why {
            Some(why) => problems.push((line, column, format!("`{DRAW_WITH} {named}`: {why}"))),
            None => out.push(External {
                stage: id.to_string(),
                reflection,
                entry: entry.to_string(),
            }),
        }
    }
    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// The pipelines of `stage` that would bind two variables on one `@group/@binding` (a vertex
/// and a fragment entry using different variables on one slot, or one name bound as two kinds
/// in two files), each with the entry and why: a build error, where wgpu would refuse the
/// layout at run time.
pub fn slot_conflicts(stage: &Stage, externals: &[External]) -> Vec<(String, String)> {
    let r = reflect(stage);
    let mut out = Vec::new();
    for p in pipelines(&r, externals) {
        let pr = p.reflection(&r);
        let used: Vec<&super::super::reflect::BindingUse> =
            p.entries.iter().flat_map(|e| &e.uses).collect();
        let entry = || p.entries.last().map_or(String::new(), |e| e.name.clone());
        for (i, a) in used.iter().enumerate() {
            if let Some(b) = used[..i]
                .iter()
                .find(|b| (b.group, b.binding) == (a.group, a.binding) && b.name != a.name)
            {
                out.push((
                    entry(),
                    format!(
                        "its pipeline `{}` would bind both `{}` and `{}` at @group({}) @binding({}): \
                         give one another slot",
                        p.module, b.name, a.name, a.group, a.binding
                    ),
                ));
            }
        }
        // wgpu refuses a bind group layout holding a binding array beside a uniform buffer.
        let in_use = |b: &&Binding| {
            used.iter().any(|u| {
                (u.group, u.binding, u.name.as_str()) == (b.group, b.binding, b.name.as_str())
            })
        };
        let bound: Vec<&Binding> = pr.bindings.iter().filter(in_use).collect();
        for array in bound
            .iter()
            .filter(|b| b.count.is_some() || b.unsized_array)
        {
            if let Some(uniform) = bound.iter().find(|b| {
                b.group == array.group
                    && matches!(b.kind, super::super::reflect::BindingKind::Uniform { .. })
            }) {
                out.push((
                    entry(),
                    format!(
                        "@group({}) holds the binding array `{}` and the uniform buffer `{}`, a \
                         bind group layout wgpu refuses: give the uniform another group",
                        array.group, array.name, uniform.name
                    ),
                ));
            }
        }
        // One slot declared in both files: the same resource only where both bind the same
        // type there.
        if let Some(x) = p
            .vertex_stage
            .and_then(|id| externals.iter().find(|x| x.stage == id))
        {
            for b in &x.reflection.bindings {
                if let Some(o) = r.bindings.iter().find(|o| {
                    (o.group, o.binding) == (b.group, b.binding)
                        && o.name == b.name
                        && !same_resource(o, b)
                }) {
                    out.push((
                        entry(),
                        format!(
                            "`{}` at @group({}) @binding({}) is `{}` here and `{}` in `{}`",
                            b.name, b.group, b.binding, o.ty, b.ty, x.stage
                        ),
                    ));
                }
            }
        }
    }
    out
}

/// The entry points of `stage` no generated pipeline holds, each with why: a fragment entry no
/// vertex entry (its file's, or one it declares to draw with) writes the inputs of (the build
/// refuses these rather than drop them).
pub fn dropped_entries(stage: &Stage, externals: &[External]) -> Vec<(String, String)> {
    let r = reflect(stage);
    let made = pipelines(&r, externals);
    r.entry_points
        .iter()
        .filter(|e| !made.iter().any(|p| p.entries.iter().any(|x| x.name == e.name)))
        .map(|e| {
            let vertex: Vec<String> = r
                .entry_points
                .iter()
                .filter(|v| v.stage == "vertex")
                .chain(externals.iter().map(External::entry_point))
                .map(|v| format!("`{}` (writes {:?})", v.name, v.stage_io))
                .collect();
            let why = if vertex.is_empty() {
                format!(
                    "a fragment entry draws with a vertex entry of the same file, or of another \
                     file named in a `{DRAW_WITH} room::stage::entry` line, and this file has none"
                )
            } else {
                format!(
                    "it reads @location {:?}, which no vertex entry it may draw with writes all of: {}",
                    e.stage_io,
                    vertex.join(", ")
                )
            };
            (e.name.clone(), why)
        })
        .collect()
}
