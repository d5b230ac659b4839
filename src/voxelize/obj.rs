//! Wavefront OBJ input through `tobj` (feature `obj`): positions, per-vertex colours
//! (`v x y z r g b`) and normals, polygons triangulated as fans. Also the npm `bunny` package's
//! positions/cells form.

#[cfg(feature = "obj")]
use std::collections::HashMap;
#[cfg(feature = "obj")]
use std::io::BufRead;
#[cfg(feature = "obj")]
use std::path::Path;

use glam::DVec3;

use super::{Mesh, STAGE};
use crate::error::Error;

#[cfg(feature = "obj")]
impl Mesh {
    /// Read a mesh from OBJ text. Every object and group goes into one mesh; vertices with
    /// bit-identical positions are welded, so a closed surface split into groups stays closed
    /// for solid voxelization (the first vertex's colour is kept). Normals given per face
    /// corner are averaged per vertex, each distinct one once. Materials, texture coordinates, points and lines are
    /// ignored.
    ///
    /// ```
    /// let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    /// let mesh = fieldkit::voxelize::Mesh::from_obj(&mut obj.as_bytes()).unwrap();
    /// assert_eq!(mesh.triangles, vec![[0, 1, 2]]);
    /// ```
    pub fn from_obj(reader: &mut impl BufRead) -> Result<Self, Error> {
        read_obj(reader).map_err(|e| Error::invalid(STAGE, format!("OBJ: {e}")))
    }

    /// [`Mesh::from_obj`] on a file.
    pub fn load_obj(path: impl AsRef<Path>) -> Result<Self, Error> {
        let path = path.as_ref();
        let file = std::fs::File::open(path)
            .map_err(|e| Error::invalid(STAGE, format!("cannot open {}: {e}", path.display())))?;
        read_obj(&mut std::io::BufReader::new(file))
            .map_err(|e| Error::invalid(STAGE, format!("OBJ {}: {e}", path.display())))
    }
}

#[cfg(feature = "obj")]
fn read_obj(reader: &mut impl BufRead) -> Result<Mesh, tobj::LoadError> {
    let options = tobj::LoadOptions {
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    let (models, _materials) =
        tobj::load_obj_buf(reader, &options, |_| Err(tobj::LoadError::OpenFileFailed))?;
    let mut mesh = Mesh::default();
    let mut welded = HashMap::<[u64; 3], u32>::new();
    let any_colour = models.iter().any(|m| !m.mesh.vertex_color.is_empty());
    let any_normal = models.iter().any(|m| !m.mesh.normals.is_empty());
    let any_uv = models.iter().any(|m| !m.mesh.texcoords.is_empty());
    let mut normal_sums = Vec::<DVec3>::new();
    let mut seen = std::collections::HashSet::new();
    for (model_index, model) in models.iter().enumerate() {
        let m = &model.mesh;
        let position = |i: usize| {
            DVec3::new(
                m.positions[3 * i] as f64,
                m.positions[3 * i + 1] as f64,
                m.positions[3 * i + 2] as f64,
            )
        };
        let mut remap = Vec::with_capacity(m.positions.len() / 3);
        for i in 0..m.positions.len() / 3 {
            let p = position(i);
            let key = p.to_array().map(f64::to_bits);
            let next = mesh.positions.len() as u32;
            let id = *welded.entry(key).or_insert(next);
            if id == next {
                mesh.positions.push(p);
                let colour = if m.vertex_color.len() >= 3 * (i + 1) {
                    let c = |k: usize| {
                        (m.vertex_color[3 * i + k].clamp(0.0, 1.0) * 255.0).round() as u8
                    };
                    [c(0), c(1), c(2), 255]
                } else {
                    [255; 4]
                };
                mesh.colors.push(colour);
                normal_sums.push(DVec3::ZERO);
            }
            remap.push(id);
        }
        for (f, tri) in m.indices.chunks_exact(3).enumerate() {
            mesh.triangles
                .push([0, 1, 2].map(|k| remap[tri[k] as usize]));
            if any_uv {
                // Texture coordinates per corner: their own indices where the file gives them
                // (seams), the position's otherwise; (0, 0) for a model without any.
                mesh.texcoords.push([0, 1, 2].map(|k| {
                    let i = m.texcoord_indices.get(3 * f + k).copied().unwrap_or(tri[k]) as usize;
                    m.texcoords
                        .get(2 * i..2 * i + 2)
                        .map_or(glam::Vec2::ZERO, |uv| glam::Vec2::new(uv[0], uv[1]))
                }));
            }
            if m.normals.is_empty() {
                continue;
            }
            for k in 0..3 {
                // Normals share the position indices unless the file gave their own; each
                // distinct normal a vertex is given counts once.
                let n = m.normal_indices.get(3 * f + k).copied().unwrap_or(tri[k]) as usize;
                let vertex = remap[tri[k] as usize];
                if !seen.insert((vertex, model_index, n)) {
                    continue;
                }
                if let Some(v) = m.normals.get(3 * n..3 * n + 3) {
                    normal_sums[vertex as usize] +=
                        DVec3::new(v[0] as f64, v[1] as f64, v[2] as f64);
                }
            }
        }
    }
    if !any_colour {
        mesh.colors.clear();
    }
    if any_normal {
        mesh.normals = normal_sums;
    }
    Ok(mesh)
}

/// The numbers of the first bracketed array after `key` in `text`, flattened.
fn nested_numbers(text: &str, key: &str) -> Result<Vec<f64>, String> {
    let at = text.find(key).ok_or(format!("no `{key}` array"))?;
    let start = at
        + text[at..]
            .find('[')
            .ok_or(format!("no array after `{key}`"))?;
    let mut depth = 0;
    let mut end = None;
    for (i, c) in text[start..].char_indices() {
        match c {
            '[' => depth += 1,
            ']' => {
                depth -= 1;
                if depth == 0 {
                    end = Some(start + i);
                    break;
                }
            }
            _ => {}
        }
    }
    let end = end.ok_or(format!("`{key}` array is not closed"))?;
    text[start..end]
        .split(|c: char| c == '[' || c == ']' || c == ',' || c.is_whitespace())
        .filter(|s| !s.is_empty())
        .map(|s| s.parse::<f64>().map_err(|e| format!("`{key}`: {s:?}: {e}")))
        .collect()
}

impl Mesh {
    /// Read a mesh from the `positions` and `cells` arrays of a JavaScript or JSON text (the
    /// "simplicial complex" layout of the stack.gl packages, which the npm package `bunny`
    /// ships as `index.js`).
    ///
    /// ```
    /// let js = "exports.positions=[[0,0,0],[1,0,0],[0,1,0]];\nexports.cells=[[0,1,2]];";
    /// let mesh = fieldkit::voxelize::Mesh::from_positions_cells(js).unwrap();
    /// assert_eq!((mesh.positions.len(), mesh.triangles.len()), (3, 1));
    /// ```
    pub fn from_positions_cells(text: &str) -> Result<Self, Error> {
        let bad = |what: String| Error::invalid(STAGE, format!("positions/cells text: {what}"));
        let p = nested_numbers(text, "positions").map_err(bad)?;
        let c = nested_numbers(text, "cells").map_err(bad)?;
        if p.len() % 3 != 0 || c.len() % 3 != 0 {
            return Err(bad(format!(
                "{} position numbers and {} cell indices: both must come in threes",
                p.len(),
                c.len()
            )));
        }
        if let Some(i) = c
            .iter()
            .find(|&&i| i < 0.0 || i.fract() != 0.0 || i > u32::MAX as f64)
        {
            return Err(bad(format!("cell index {i} is not a vertex index")));
        }
        Ok(Mesh {
            positions: p.chunks(3).map(|v| DVec3::new(v[0], v[1], v[2])).collect(),
            triangles: c
                .chunks(3)
                .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
                .collect(),
            ..Mesh::default()
        })
    }
}
