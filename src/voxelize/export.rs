//! Occupancy to files other tools read: binvox (Patrick Min's format, run-length encoded) and
//! MagicaVoxel's `.vox`.

use crate::error::Error;

use super::Grid;

const STAGE: &str = "voxelize::export";

/// binvox: a text header (`dim`, `translate`, `scale`) and run-length pairs (value, count ≤ 255)
/// over the voxels in binvox order (y fastest, then z, then x). `occupied` is one bool per
/// voxel, x fastest, as [`super::Surface::read`] gives it. The world box is `grid`'s, scaled by
/// its longest side as binvox expects.
pub fn binvox(occupied: &[bool], grid: &Grid) -> Result<Vec<u8>, Error> {
    let [nx, ny, nz] = grid.size.map(|n| n as usize);
    check_len(occupied, nx * ny * nz)?;
    let longest = nx.max(ny).max(nz) as f64 * grid.voxel;
    let mut out = format!(
        "#binvox 1\ndim {nx} {ny} {nz}\ntranslate {} {} {}\nscale {}\ndata\n",
        grid.origin.x, grid.origin.y, grid.origin.z, longest
    )
    .into_bytes();
    let mut run: Option<(bool, u8)> = None;
    for x in 0..nx {
        for z in 0..nz {
            for y in 0..ny {
                let v = occupied[(z * ny + y) * nx + x];
                run = match run {
                    Some((value, count)) if value == v && count < 255 => Some((value, count + 1)),
                    Some((value, count)) => {
                        out.extend_from_slice(&[value as u8, count]);
                        Some((v, 1))
                    }
                    None => Some((v, 1)),
                };
            }
        }
    }
    if let Some((value, count)) = run {
        out.extend_from_slice(&[value as u8, count]);
    }
    Ok(out)
}

/// MagicaVoxel `.vox` (version 150): one model, every occupied voxel with palette index 1.
/// MagicaVoxel models hold at most 256 voxels per side: larger grids are refused.
pub fn vox(occupied: &[bool], size: [u32; 3]) -> Result<Vec<u8>, Error> {
    let [nx, ny, nz] = size.map(|n| n as usize);
    check_len(occupied, nx * ny * nz)?;
    if let Some(&big) = size.iter().find(|&&n| n > 256) {
        return Err(Error::Size {
            stage: STAGE,
            what: "grid side for a .vox model",
            got: big as u64,
            max: 256,
        });
    }
    let mut xyzi = Vec::new();
    let mut count = 0u32;
    for (i, _) in occupied.iter().enumerate().filter(|&(_, &o)| o) {
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        // MagicaVoxel is z-up: our y (up) is its z.
        xyzi.extend_from_slice(&[x as u8, z as u8, y as u8, 1]);
        count += 1;
    }
    let chunk = |id: &[u8; 4], content: &[u8], children: &[u8]| {
        let mut c = id.to_vec();
        c.extend_from_slice(&(content.len() as u32).to_le_bytes());
        c.extend_from_slice(&(children.len() as u32).to_le_bytes());
        c.extend_from_slice(content);
        c.extend_from_slice(children);
        c
    };
    let mut size_content = Vec::new();
    for n in [nx, nz, ny] {
        size_content.extend_from_slice(&(n as u32).to_le_bytes());
    }
    let mut xyzi_content = count.to_le_bytes().to_vec();
    xyzi_content.extend_from_slice(&xyzi);
    let mut children = chunk(b"SIZE", &size_content, &[]);
    children.extend(chunk(b"XYZI", &xyzi_content, &[]));
    let mut out = b"VOX ".to_vec();
    out.extend_from_slice(&150u32.to_le_bytes());
    out.extend(chunk(b"MAIN", &[], &children));
    Ok(out)
}

fn check_len(occupied: &[bool], want: usize) -> Result<(), Error> {
    if occupied.len() != want {
        return Err(Error::Invalid {
            stage: STAGE,
            what: format!("{} voxels given, the grid has {want}", occupied.len()),
        });
    }
    Ok(())
}
