//! 3D jump flooding (Rong & Tan): seeds from a volume, then passes of halving steps over
//! packed seeds or point keys.

use std::sync::Arc;

use super::buffers::{Pool, view};
use super::check::{check_len, check_size_3d, check_volume, voxels};
use super::options::Marks;
use crate::bind::{ComputePipeline, KeptBound};
use crate::error::Error;
use crate::gpu::{KeptUniform, Record, uniform_buffer as uniform};
use crate::shaders::distance::{jfa3_seed, jfa3_step};

/// 3D jump flooding's stages, run alone: [`super::Distance3d::jfa`] (its
/// [`super::Distance3d::encode`] with [`super::Method::Jfa`] runs them in turn and resolves).
pub struct Jfa3d {
    seed: ComputePipeline<jfa3_seed::seed::Entry>,
    jump: ComputePipeline<jfa3_step::jump::Entry>,
    jump_points: ComputePipeline<jfa3_step::jump_points::Entry>,
    pool: Arc<Pool>,
    /// Each step's uniform and bind groups, kept from call to call: a flood run every frame
    /// on one grid (its field recycled) makes no object a frame.
    steps: [KeptStep; KEPT_STEPS],
}

/// Steps whose objects are kept: more than any flood of the largest grid takes (a side of
/// 2048 floods in 11 halving steps, 13 with JFA+2).
const KEPT_STEPS: usize = 24;

#[derive(Default)]
struct KeptStep {
    params: KeptUniform,
    jump: KeptBound<jfa3_step::jump::Entry>,
    jump_points: KeptBound<jfa3_step::jump_points::Entry>,
}

impl Jfa3d {
    pub(crate) fn new(device: &wgpu::Device, pool: Arc<Pool>) -> Result<Self, Error> {
        Ok(Self {
            seed: ComputePipeline::new(device)?,
            jump: ComputePipeline::new(device)?,
            jump_points: ComputePipeline::new(device)?,
            pool,
            steps: std::array::from_fn(|_| KeptStep::default()),
        })
    }

    /// Seed stage alone: a new buffer of packed seeds from the marked voxels.
    pub fn encode_seed(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        marks: Marks,
    ) -> Result<wgpu::Buffer, Error> {
        let size = check_volume(device, marks.volume)?;
        let out = self.pool.field_buffer(device, "nearest seed", size);
        let params = uniform(
            device,
            "seed params",
            &jfa3_seed::SeedParams {
                size: size.into(),
                threshold: marks.inside.threshold(),
                invert: marks.invert as u32,
            },
        );
        let vv = view(marks.volume);
        self.seed.record(
            device,
            rec,
            &jfa3_seed::seed::Resources {
                params: (&params).into(),
                volume: (&vv).into(),
                nearest: (&out).into(),
            },
            ComputePipeline::<jfa3_seed::seed::Entry>::groups_for(size),
            "seed",
        )?;
        Ok(out)
    }

    /// JFA passes of `steps` over the seeds in `nearest` (ping-ponging with a second buffer):
    /// packed seeds, or, with `points` (vec4 per point, voxel coordinates), keys into that
    /// table. Returns the buffer holding the result.
    pub fn encode_flood(
        &self,
        device: &wgpu::Device,
        rec: &mut impl Record,
        nearest: wgpu::Buffer,
        size: [u32; 3],
        steps: &[u32],
        points: Option<&wgpu::Buffer>,
    ) -> Result<wgpu::Buffer, Error> {
        check_size_3d(device, size)?;
        check_len(jfa3_step::STAGE, "field", &nearest, voxels(size) * 4, size)?;
        if steps.contains(&0) {
            return Err(Error::Invalid {
                stage: jfa3_step::STAGE,
                what: "step 0".into(),
            });
        }
        let other = self.pool.field_buffer(device, "jfa ping-pong", size);
        let (mut a, mut b) = (nearest, other);
        let groups = ComputePipeline::<jfa3_step::jump::Entry>::groups_for(size);
        let fresh = KeptStep::default();
        for (k, &step) in steps.iter().enumerate() {
            // A step past the kept ones keeps nothing beyond this call.
            let kept = self.steps.get(k).unwrap_or(&fresh);
            let params = kept.params.get(
                device,
                "jfa jump params",
                &jfa3_step::JumpParams {
                    size: size.into(),
                    step,
                },
            );
            match points {
                None => {
                    self.jump.record_kept(
                        device,
                        rec,
                        &kept.jump,
                        &jfa3_step::jump::Resources {
                            params: (&params).into(),
                            src: (&a).into(),
                            dst: (&b).into(),
                        },
                        groups,
                        &format!("jump {step}"),
                    )?;
                }
                Some(pts) => {
                    self.jump_points.record_kept(
                        device,
                        rec,
                        &kept.jump_points,
                        &jfa3_step::jump_points::Resources {
                            params: (&params).into(),
                            src: (&a).into(),
                            dst: (&b).into(),
                            points: pts.into(),
                        },
                        groups,
                        &format!("jump {step}"),
                    )?;
                }
            }
            std::mem::swap(&mut a, &mut b);
        }
        Ok(a)
    }
}
