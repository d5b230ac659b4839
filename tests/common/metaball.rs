//! What the metaball render tests share: a small camera, a shot through the SDF march or a
//! direct tracer read back per pixel, and the shot held against f64 bisection on the analytic
//! field.

use fieldkit::gpu::{Context, read_texture};
use fieldkit::metaball::{BlobBins, Instances, MetaballField, Metaballs, Settings, cpu};
use fieldkit::metaball::{Direct, MarchField, Output, RaymarchSettings, Raymarcher};
use fieldkit::view::{Targets, View};
use glam::{DVec3, Mat4, Vec3, Vec4};

use super::metaball_field;

pub const W: u32 = 64;

pub const H: u32 = 48;

pub struct Shot {
    /// Per pixel: Some((normal, distance from the near plane)).
    pub hits: Vec<Option<(Vec3, f32)>>,
    pub depth: Vec<f32>,
    pub colour: Vec<[f32; 4]>,
}

pub fn camera(eye: Vec3, target: Vec3, reversed: bool) -> View {
    camera_near(eye, target, reversed, 0.05)
}

pub fn camera_near(eye: Vec3, target: Vec3, reversed: bool, near: f32) -> View {
    let far = 40.0;
    let proj = if reversed {
        glam::camera::rh::proj::directx::perspective(0.7, W as f32 / H as f32, far, near)
    } else {
        glam::camera::rh::proj::directx::perspective(0.7, W as f32 / H as f32, near, far)
    };
    View {
        view_proj: proj * glam::camera::rh::view::look_at_mat4(eye, target, Vec3::Y),
        viewport: [W, H],
        reversed_z: reversed,
        origin: [0, 0],
    }
}

/// What draws the surface: the SDF-texture march (of a metaball field or any field in the
/// march's format), or a direct tracer over blob bins.
#[derive(Clone, Copy)]
pub enum Tracer<'a> {
    Sdf(&'a MetaballField),
    Field(MarchField<'a>),
    Direct(&'a BlobBins, Direct),
}

impl<'a> From<&'a MetaballField> for Tracer<'a> {
    fn from(f: &'a MetaballField) -> Self {
        Tracer::Sdf(f)
    }
}

/// A raymarcher drawing into `colour` over a `Depth32Float` target, depth standard or
/// `reversed`.
pub fn raymarcher(ctx: &Context, colour: wgpu::TextureFormat, reversed: bool) -> Raymarcher {
    let depth = wgpu::TextureFormat::Depth32Float;
    Raymarcher::new(&ctx.device, &ctx.queue, colour, depth, reversed).unwrap()
}

/// Render with `tracer` into a float target over a depth buffer cleared to `clear_depth`.
pub fn shoot<'a>(
    ctx: &Context,
    tracer: impl Into<Tracer<'a>>,
    view: &View,
    local_to_world: Mat4,
    settings: &RaymarchSettings,
    clear_depth: f32,
) -> Shot {
    let device = &ctx.device;
    let targets = Targets::new(
        device,
        [W, H],
        wgpu::TextureFormat::Rgba32Float,
        wgpu::TextureFormat::Depth32Float,
    );
    let (cv, dv) = (&targets.colour_view, &targets.depth_view);
    let marcher = raymarcher(ctx, wgpu::TextureFormat::Rgba32Float, view.reversed_z);
    let mut enc = ctx.encoder("shoot");
    // Colour cleared to zero (alpha 0 marks "not drawn"), depth to the caller's value.
    targets.clear(&mut enc, wgpu::Color::TRANSPARENT, clear_depth);
    match tracer.into() {
        Tracer::Sdf(field) => marcher.encode(
            device,
            &mut enc,
            cv,
            dv,
            field,
            local_to_world,
            view,
            settings,
        ),
        Tracer::Field(field) => marcher
            .encode_march_field(device, &mut enc, &field, local_to_world, view, settings)
            .and_then(|m| match m {
                Some(m) => marcher
                    .encode_composite(device, &mut enc, cv, dv, &m)
                    .map(|()| true),
                None => Ok(false),
            }),
        Tracer::Direct(bins, method) => marcher.encode_direct(
            device,
            &mut enc,
            cv,
            dv,
            bins,
            method,
            local_to_world,
            view,
            settings,
        ),
    }
    .unwrap();
    ctx.submit_and_wait("shoot", enc).unwrap();
    let colour: Vec<[f32; 4]> = read_texture(ctx, &targets.colour).unwrap();
    let depth: Vec<f32> = read_texture(ctx, &targets.depth).unwrap();
    let hits = colour
        .iter()
        .map(|c| (c[3] != 0.0).then(|| (Vec3::new(c[0], c[1], c[2]), c[3] - 1.0)))
        .collect();
    Shot {
        hits,
        depth,
        colour,
    }
}

pub fn normals() -> RaymarchSettings {
    RaymarchSettings {
        output: Output::Normal,
        ..RaymarchSettings::default()
    }
}

/// The pixel's ray as the shader builds it: from the near plane towards the far plane.
pub fn ray(view: &View, x: u32, y: u32) -> (DVec3, DVec3, f64) {
    let inv = view.view_proj.as_dmat4().inverse();
    let ndc = glam::DVec2::new(
        (x as f64 + 0.5) / W as f64 * 2.0 - 1.0,
        1.0 - (y as f64 + 0.5) / H as f64 * 2.0,
    );
    let (zn, zf) = if view.reversed_z {
        (1.0, 0.0)
    } else {
        (0.0, 1.0)
    };
    let near = inv.project_point3(ndc.extend(zn));
    let far = inv.project_point3(ndc.extend(zf));
    ((near), (far - near).normalize(), (far - near).length())
}

pub struct Agreement {
    pub silhouette_off: usize,
    pub hits: usize,
    /// Along the ray, where the ray meets the surface at 60° or steeper (grazing rays turn a
    /// small offset of the surface into a long one along the ray).
    pub max_depth_err: f64,
    /// Distance from each hit point to the analytic surface, (ρ − T)/|∇ρ|, all hits.
    pub max_surface_err: f64,
    pub max_normal_deg: f64,
}

impl Agreement {
    /// Print what `what` measured, then hold it to `bound`: more hits than `bound.hits`, at most
    /// `bound.silhouette_off` silhouette pixels that differ, each error below the bound's.
    pub fn check(&self, what: &str, bound: &Agreement) {
        println!(
            "{what}: {} hits, {} silhouette pixels differ, depth ≤ {:.4} cells, hit point ≤ \
             {:.4} cells off, normal ≤ {:.3}°",
            self.hits,
            self.silhouette_off,
            self.max_depth_err,
            self.max_surface_err,
            self.max_normal_deg
        );
        assert!(self.hits > bound.hits, "{what}: {} hits", self.hits);
        let off = self.silhouette_off;
        assert!(
            off <= bound.silhouette_off,
            "{what}: {off} silhouette pixels"
        );
        let depth = self.max_depth_err;
        assert!(depth < bound.max_depth_err, "{what}: depth {depth}");
        let surface = self.max_surface_err;
        assert!(
            surface < bound.max_surface_err,
            "{what}: hit point {surface}"
        );
        let normal = self.max_normal_deg;
        assert!(normal < bound.max_normal_deg, "{what}: normal {normal}");
    }
}

/// Compare a shot with f64 bisection on the analytic field (identity placement).
pub fn against_analytic(
    shot: &Shot,
    view: &View,
    voxels: &[Vec4],
    settings: &Settings,
    cell: f64,
) -> Agreement {
    against_analytic_placed(shot, view, voxels, settings, cell, Mat4::IDENTITY)
}

/// [`against_analytic`] for a field placed by `place`: each pixel's world ray is moved into
/// local space, bisected there, and the hit and its normal (inverse transpose) brought back.
/// Depth errors are world lengths, surface errors local ones, both in cells.
pub fn against_analytic_placed(
    shot: &Shot,
    view: &View,
    voxels: &[Vec4],
    settings: &Settings,
    cell: f64,
    place: Mat4,
) -> Agreement {
    let place = place.as_dmat4();
    let inv = place.inverse();
    let normal_to_world = glam::DMat3::from_mat4(inv).transpose();
    let mut a = Agreement {
        silhouette_off: 0,
        hits: 0,
        max_depth_err: 0.0,
        max_surface_err: 0.0,
        max_normal_deg: 0.0,
    };
    for y in 0..H {
        for x in 0..W {
            let (o, d, len) = ray(view, x, y);
            let (ol, far_l) = (inv.transform_point3(o), inv.transform_point3(o + d * len));
            let dl = (far_l - ol).normalize();
            let len_l = (far_l - ol).length();
            let exact = cpu::ray_hit(voxels, 1.0, settings, ol, dl, len_l.min(30.0), 0.01);
            let got = shot.hits[(y * W + x) as usize];
            match (exact, got) {
                (Some(t), Some((n, dist))) => {
                    a.hits += 1;
                    let hit = place.transform_point3(ol + dl * t);
                    let g_local = -cpu::gradient_at(voxels, 1.0, settings, ol + dl * t);
                    let g = normal_to_world * g_local;
                    if g.normalize().dot(-d) > 0.5 {
                        let t_world = (hit - o).length();
                        a.max_depth_err = a.max_depth_err.max((dist as f64 - t_world).abs() / cell);
                    }
                    let p = inv.transform_point3(o + d * dist as f64);
                    let r = cpu::density_at(voxels, 1.0, settings, p) - settings.threshold as f64;
                    let gp = cpu::gradient_at(voxels, 1.0, settings, p).length();
                    if gp > 1e-9 {
                        a.max_surface_err = a.max_surface_err.max((r / gp).abs() / cell);
                    }
                    if g.length() > 1e-9 {
                        let cos = (g.normalize().dot(n.as_dvec3().normalize())).clamp(-1.0, 1.0);
                        a.max_normal_deg = a.max_normal_deg.max(cos.acos().to_degrees());
                    }
                }
                (None, None) => {}
                _ => a.silhouette_off += 1,
            }
        }
    }
    a
}

pub fn blob_settings() -> Settings {
    Settings {
        cells_per_edge: 12.0,
        ..Settings::default()
    }
}

pub fn one_blob(ctx: &Context) -> (Vec<Vec4>, MetaballField) {
    let voxels = vec![Vec4::new(0.0, 0.0, 0.0, 1.0)];
    let field = metaball_field(ctx, &voxels, 1.0, &blob_settings());
    (voxels, field)
}

pub fn count(shot: &Shot) -> usize {
    shot.hits.iter().filter(|h| h.is_some()).count()
}

/// Blob bins over the fitted grid of `voxels` (edge 1).
pub fn blob_bins(ctx: &Context, voxels: &[Vec4], s: &Settings) -> BlobBins {
    let grid = s.fit_grid(voxels, 1.0).unwrap().unwrap();
    run_stage(ctx, voxels, |balls, enc, inst| {
        balls.encode_bins(&ctx.device, enc, inst, &grid, 1.0, s)
    })
}

pub fn three_blobs() -> Vec<Vec4> {
    vec![
        Vec4::new(-0.6, 0.0, 0.0, 1.0),
        Vec4::new(0.6, 0.0, 0.0, 1.0),
        Vec4::new(0.1, 0.95, -0.2, 0.8),
    ]
}

/// Mean steps per pixel whose ray enters the box, from the step heat map.
pub fn mean_steps(shot: &Shot, max_steps: u32) -> f64 {
    let steps: Vec<f64> = shot
        .colour
        .iter()
        .filter(|c| c[3] != 0.0)
        .map(|c| ((c[0] + c[1] + c[2]) as f64 / 3.0 * max_steps as f64).round())
        .collect();
    steps.iter().sum::<f64>() / steps.len().max(1) as f64
}

/// `voxels` uploaded to a new `Metaballs`, then `stage` recorded into one encoder, submitted and
/// waited for: what a single-stage test runs.
pub fn run_stage<R>(
    ctx: &Context,
    voxels: &[Vec4],
    stage: impl FnOnce(&Metaballs, &mut wgpu::CommandEncoder, &Instances) -> Result<R, fieldkit::Error>,
) -> R {
    let balls = Metaballs::new(&ctx.device).unwrap();
    let inst = balls.upload(&ctx.device, &ctx.queue, voxels).unwrap();
    let mut enc = ctx.encoder("metaball stage");
    let out = stage(&balls, &mut enc, &inst).unwrap();
    ctx.submit_and_wait("metaball stage", enc).unwrap();
    out
}
