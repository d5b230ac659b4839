//! 2D distance by jump flooding (JFA) from a seed texture, with the variants that trade speed
//! for accuracy, resolved to unsigned or signed distance. [`super::Distance2d`] is the 2D API
//! (exact by default); [`Jfa2d`] runs JFA alone and each of its stages on its own.

use super::SeedRule;
use super::seeds::{STAGE, check_seed_texture, check_size};
use crate::bind::{ComputePipeline, Entry};
use crate::error::Error;
use crate::gpu::Record;
use crate::shaders::distance::{jfa_resolve, jfa_seed, jfa_step};

/// Which passes run: plain JFA, or with extra passes of step 1 or 2 that repair its errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum Variant {
    /// Steps N/2, N/4, …, 1 (N the next power of two at or above the largest side).
    Jfa,
    /// JFA, then one pass of step 1.
    JfaPlus1,
    /// JFA, then passes of step 2 and 1 (Rong & Tan's most accurate cheap variant).
    #[default]
    JfaPlus2,
    /// One pass of step 1 first, then JFA.
    OnePlusJfa,
    /// Step 1, JFA, then steps 2 and 1.
    OnePlusJfaPlus2,
}

impl Variant {
    /// Every variant, fewest passes first.
    pub const ALL: [Variant; 5] = [
        Variant::Jfa,
        Variant::JfaPlus1,
        Variant::JfaPlus2,
        Variant::OnePlusJfa,
        Variant::OnePlusJfaPlus2,
    ];

    /// The variant's name as the README's table writes it.
    pub fn name(self) -> &'static str {
        match self {
            Variant::Jfa => "JFA",
            Variant::JfaPlus1 => "JFA+1",
            Variant::JfaPlus2 => "JFA+2",
            Variant::OnePlusJfa => "1+JFA",
            Variant::OnePlusJfaPlus2 => "1+JFA+2",
        }
    }

    /// Step lengths of every pass, in order, for a grid whose largest side is `max_side`.
    pub fn steps(self, max_side: u32) -> Vec<u32> {
        let mut jfa = Vec::new();
        // The first step is half the next power of two at or above the largest side: the steps then
        // sum to at least max_side - 1, so every texel can reach every other.
        let mut step = max_side.max(1).next_power_of_two() / 2;
        while step >= 1 {
            jfa.push(step);
            step /= 2;
        }
        match self {
            Variant::Jfa => jfa,
            Variant::JfaPlus1 => [jfa, vec![1]].concat(),
            Variant::JfaPlus2 => [jfa, vec![2, 1]].concat(),
            Variant::OnePlusJfa => [vec![1], jfa].concat(),
            Variant::OnePlusJfaPlus2 => [vec![1], jfa, vec![2, 1]].concat(),
        }
    }
}

/// What [`Jfa2d::encode`] computes.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct JfaSettings2d {
    /// Which passes run.
    pub variant: Variant,
    /// Treat the seed texture as a mask (non-zero inside) and produce signed distance,
    /// negative inside.
    pub signed: bool,
    /// World units per texel; distances are multiplied by it.
    pub texel_size: f32,
    /// Which texels are seeds (default: red above 0).
    #[cfg_attr(feature = "serde", serde(default))]
    pub seeds: SeedRule,
}

impl Default for JfaSettings2d {
    fn default() -> Self {
        Self {
            variant: Variant::default(),
            signed: false,
            texel_size: 1.0,
            seeds: SeedRule::default(),
        }
    }
}

impl JfaSettings2d {
    /// The defaults with a signed field, negative inside:
    /// `JfaSettings2d { signed: true, ..JfaSettings2d::default() }`.
    pub fn signed() -> Self {
        Self {
            signed: true,
            ..Self::default()
        }
    }
}

/// The result of a 2D distance computation, on the GPU.
pub struct JfaField2d {
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// `R32Uint`: nearest seed per texel, packed ([`unpack_seed`](super::unpack_seed)). For a signed field, the
    /// nearest *inside* texel.
    pub nearest: wgpu::Texture,
    /// `R32Uint`: for a signed field, the nearest *outside* texel.
    pub nearest_outside: Option<wgpu::Texture>,
    /// `R32Float`: distance to the nearest seed (signed: negative inside), times `texel_size`.
    pub distance: wgpu::Texture,
}

/// The 2D JFA pipelines. Create once, encode many times.
pub struct Jfa2d {
    seed: ComputePipeline<jfa_seed::seed::Entry>,
    jump: ComputePipeline<jfa_step::jump::Entry>,
    resolve_unsigned: ComputePipeline<jfa_resolve::resolve_unsigned::Entry>,
    resolve_signed: ComputePipeline<jfa_resolve::resolve_signed::Entry>,
}

fn texture(
    device: &wgpu::Device,
    label: &str,
    w: u32,
    h: u32,
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    crate::gpu::texture(
        device,
        label,
        [w, h, 1],
        wgpu::TextureDimension::D2,
        format,
        wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
    )
}

use crate::gpu::uniform_buffer as uniform;

fn view(t: &wgpu::Texture) -> wgpu::TextureView {
    t.create_view(&Default::default())
}

fn groups<E: Entry>(w: u32, h: u32) -> [u32; 3] {
    ComputePipeline::<E>::groups_for([w, h, 1])
}

impl Jfa2d {
    /// Create the JFA pipelines.
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Ok(Self {
            seed: ComputePipeline::new(device)?,
            jump: ComputePipeline::new(device)?,
            resolve_unsigned: ComputePipeline::new(device)?,
            resolve_signed: ComputePipeline::new(device)?,
        })
    }

    /// Seed stage alone: a new `R32Uint` texture of packed seeds (red above 0 marks a seed).
    pub fn encode_seed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        seeds: &wgpu::Texture,
        invert: bool,
    ) -> Result<wgpu::Texture, Error> {
        self.encode_seed_with(device, rec, seeds, invert, &SeedRule::default())
    }

    /// [`Jfa2d::encode_seed`] with `rule` choosing the seeds.
    pub fn encode_seed_with(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        seeds: &wgpu::Texture,
        invert: bool,
        rule: &SeedRule,
    ) -> Result<wgpu::Texture, Error> {
        rule.check()?;
        let (w, h) = check_seed_texture(device, seeds)?;
        let out = texture(device, "jfa nearest", w, h, wgpu::TextureFormat::R32Uint);
        let params = uniform(
            device,
            "jfa seed params",
            &jfa_seed::SeedParams {
                size: glam::uvec2(w, h),
                invert: invert as u32,
                threshold: rule.threshold(),
                channels: rule.weights(),
            },
        );
        let (sv, ov) = (view(seeds), view(&out));
        self.seed.record(
            device,
            rec,
            &jfa_seed::seed::Resources {
                params: (&params).into(),
                seeds: (&sv).into(),
                nearest: (&ov).into(),
            },
            groups::<jfa_seed::seed::Entry>(w, h),
            "seed",
        )?;
        Ok(out)
    }

    /// One jump pass alone, from `src` into `dst` (both `R32Uint`, same size).
    pub fn encode_jump(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        src: &wgpu::Texture,
        dst: &wgpu::Texture,
        step: u32,
    ) -> Result<(), Error> {
        let (w, h) = (src.width(), src.height());
        check_size(device, w, h)?;
        if step == 0 {
            return Err(Error::Invalid {
                stage: jfa_step::STAGE,
                what: "step 0".into(),
            });
        }
        if dst.size() != src.size() {
            return Err(Error::Invalid {
                stage: jfa_step::STAGE,
                what: format!("src is {:?}, dst is {:?}", src.size(), dst.size()),
            });
        }
        let params = uniform(
            device,
            "jfa jump params",
            &jfa_step::JumpParams {
                size: glam::uvec2(w, h),
                step,
            },
        );
        let (sv, dv) = (view(src), view(dst));
        self.jump.record(
            device,
            rec,
            &jfa_step::jump::Resources {
                params: (&params).into(),
                src: (&sv).into(),
                dst: (&dv).into(),
            },
            groups::<jfa_step::jump::Entry>(w, h),
            &format!("jump {step}"),
        )
    }

    /// Run the passes of `steps` over `nearest`, ping-ponging with a second texture; returns the
    /// texture holding the result.
    pub fn encode_flood(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Texture,
        steps: &[u32],
    ) -> Result<wgpu::Texture, Error> {
        let other = texture(
            device,
            "jfa ping-pong",
            nearest.width(),
            nearest.height(),
            wgpu::TextureFormat::R32Uint,
        );
        let (mut a, mut b) = (nearest, other);
        for &step in steps {
            self.encode_jump(device, rec, &a, &b, step)?;
            std::mem::swap(&mut a, &mut b);
        }
        Ok(a)
    }

    /// Resolve stage alone: distance from nearest-seed texture(s).
    pub fn encode_resolve(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: &wgpu::Texture,
        nearest_outside: Option<&wgpu::Texture>,
        texel_size: f32,
    ) -> Result<wgpu::Texture, Error> {
        if !(texel_size.is_finite() && texel_size > 0.0) {
            return Err(Error::Invalid {
                stage: jfa_resolve::STAGE,
                what: format!("texel_size must be finite and positive, got {texel_size}"),
            });
        }
        let (w, h) = (nearest.width(), nearest.height());
        check_size(device, w, h)?;
        let out = texture(device, "jfa distance", w, h, wgpu::TextureFormat::R32Float);
        let params = uniform(
            device,
            "jfa resolve params",
            &jfa_resolve::ResolveParams {
                size: glam::uvec2(w, h),
                texel_size,
            },
        );
        let (nv, dv) = (view(nearest), view(&out));
        let groups = groups::<jfa_resolve::resolve_unsigned::Entry>(w, h);
        match nearest_outside {
            None => self.resolve_unsigned.record(
                device,
                rec,
                &jfa_resolve::resolve_unsigned::Resources {
                    params: (&params).into(),
                    nearest: (&nv).into(),
                    distance: (&dv).into(),
                },
                groups,
                "resolve",
            )?,
            Some(o) => {
                let ov = view(o);
                self.resolve_signed.record(
                    device,
                    rec,
                    &jfa_resolve::resolve_signed::Resources {
                        params: (&params).into(),
                        nearest: (&nv).into(),
                        nearest_outside: (&ov).into(),
                        distance: (&dv).into(),
                    },
                    groups,
                    "resolve",
                )?
            }
        }
        Ok(out)
    }

    /// The whole chain: seed → JFA passes → resolve, recorded into `rec` (a command encoder, or
    /// [`crate::gpu::Profiler::record`] to time each pass).
    pub fn encode(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        seeds: &wgpu::Texture,
        options: &JfaSettings2d,
    ) -> Result<JfaField2d, Error> {
        let (w, h) = check_seed_texture(device, seeds)?;
        if !(options.texel_size.is_finite() && options.texel_size > 0.0) {
            return Err(Error::Invalid {
                stage: STAGE,
                what: format!(
                    "texel_size must be finite and positive, got {}",
                    options.texel_size
                ),
            });
        }
        let steps = options.variant.steps(w.max(h));
        let inside = self.encode_seed_with(device, rec, seeds, false, &options.seeds)?;
        let nearest = self.encode_flood(device, rec, inside, &steps)?;
        let nearest_outside = if options.signed {
            let outside = self.encode_seed_with(device, rec, seeds, true, &options.seeds)?;
            Some(self.encode_flood(device, rec, outside, &steps)?)
        } else {
            None
        };
        let distance = self.encode_resolve(
            device,
            rec,
            &nearest,
            nearest_outside.as_ref(),
            options.texel_size,
        )?;
        Ok(JfaField2d {
            width: w,
            height: h,
            nearest,
            nearest_outside,
            distance,
        })
    }
}
