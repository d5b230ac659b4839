//! Pipelines made from a stage's interface table, and the override constants that specialise
//! them.

use super::*;

use super::groups::bind_groups;

/// The runtime checks fieldkit's own stages are built with: wgpu's defaults (indices clamped to
/// their arrays; buffers and images left to the driver's robust access) less *loop bounding*,
/// the 64-bit counter naga adds to every loop so that a loop that never ends cannot be assumed
/// unreachable by the driver's compiler. Every loop in `shaders/` ends by construction (a
/// counted `for`, a step count, a stack that only shrinks, a walk along an array's
/// bounds), and the counter costs a register pair, a compare and a carry per iteration: measured
/// on the H100 (`cargo xtask bench distance --exact-only`, clocks held, one command running a
/// build with it and one without), the exact transform took 0.709 ms without it against 0.873
/// with it at 256³, 6.01 against 6.77 at 512³ and 2.55 against 2.95 at 8192², and the
/// workgroup column pass went from 47 to 41 registers. Entries whose [`EntryInfo::loops_end`]
/// is false (a shader no one has checked) keep every check.
pub const fn stage_checks() -> wgpu::ShaderRuntimeChecks {
    let mut checks = wgpu::ShaderRuntimeChecks::checked();
    checks.force_loop_bounding = false;
    checks
}

/// The shader module of `info`, from its compiled-in source, or from `relinked` (hot reload:
/// every runtime check kept, as no one has read its loops).
pub(crate) fn module(
    device: &wgpu::Device,
    info: &EntryInfo,
    relinked: Option<&str>,
) -> wgpu::ShaderModule {
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(info.path),
        source: wgpu::ShaderSource::Wgsl(relinked.unwrap_or(info.source).into()),
    };
    if !info.loops_end || relinked.is_some() {
        return device.create_shader_module(desc);
    }
    // SAFETY: `stage_checks` keeps every bounds check and turns off only loop bounding, whose
    // contract is that the shader has no infinite loop: `loops_end` says each loop of this one
    // ends (fieldkit's own stages, see `stage_checks`).
    unsafe { device.create_shader_module_trusted(desc, stage_checks()) }
}

/// A stage's `override` constants as one typed value: the generated `Overrides` struct of
/// every stage that declares overrides implements it, so pipelines are specialised through
/// typed fields and a renamed override is a compile error, never a string that no longer
/// matches.
pub trait Constants: Copy + PartialEq + Send + Sync + 'static {
    /// `(name, value)` for each override to set, as pipelines take them.
    fn constants(&self) -> Vec<(&'static str, f64)>;
}

/// Compute pipelines of one entry point `E` specialised by override values `O` (its stage's
/// generated `Overrides`), each made on first use and kept, keyed on the typed value (for
/// overrides that take many values, such as a workgroup array's length).
// Used by the techniques' stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct Variants<E, O> {
    made: std::sync::Mutex<Vec<Made<E, O>>>,
}

/// A pipeline made for a key.
type Made<E, O> = (VariantKey<O>, std::sync::Arc<ComputePipeline<E>>);

/// The typed overrides and the zero-fill choice.
pub(crate) type VariantKey<O> = (O, bool);

impl<E, O> Default for Variants<E, O> {
    fn default() -> Self {
        Self {
            made: Default::default(),
        }
    }
}

// Used by the techniques' stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl<E: Entry, O: Constants> Variants<E, O> {
    /// The pipeline for `overrides`, made now if it is the first use.
    pub(crate) fn get(
        &self,
        device: &wgpu::Device,
        overrides: &O,
        zero_initialize_workgroup_memory: bool,
    ) -> Result<std::sync::Arc<ComputePipeline<E>>, Error> {
        let key = (*overrides, zero_initialize_workgroup_memory);
        let find = |made: &[Made<E, O>]| made.iter().find(|(k, _)| *k == key).map(|m| m.1.clone());
        if let Some(p) = find(&self.lock()) {
            return Ok(p);
        }
        // Made without the lock: a frame asking for a variant already made (or `has`) never
        // waits for another thread compiling a new one. Two threads making the same variant at
        // once both compile it; the first kept is used.
        let p = std::sync::Arc::new(ComputePipeline::with_options(
            device,
            &overrides.constants(),
            zero_initialize_workgroup_memory,
        )?);
        let mut made = self.lock();
        if let Some(first) = find(&made) {
            return Ok(first);
        }
        made.push((key, p.clone()));
        Ok(p)
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Vec<Made<E, O>>> {
        self.made.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Whether the pipeline for `overrides` is made (a call to [`Self::get`] would not make it).
    pub(crate) fn has(&self, overrides: &O, zero_initialize_workgroup_memory: bool) -> bool {
        let key = (*overrides, zero_initialize_workgroup_memory);
        self.lock().iter().any(|(k, _)| *k == key)
    }
}

/// A compute pipeline for a generated entry point `E`.
pub struct ComputePipeline<E> {
    /// The wgpu pipeline.
    pub pipeline: wgpu::ComputePipeline,
    layouts: Vec<(u32, wgpu::BindGroupLayout)>,
    /// The shader's slots, unsized binding arrays at the lengths the pipeline was made with.
    slots: Vec<Slot>,
    /// Its workgroup size, with the overrides it was made with.
    workgroup_size: [u32; 3],
    _e: PhantomData<E>,
}

impl<E: Entry> ComputePipeline<E> {
    /// Create the pipeline; wgpu validation errors come back as [`Error::Wgpu`].
    pub fn new(device: &wgpu::Device) -> Result<Self, Error> {
        Self::with_overrides(device, &[])
    }

    /// The pipeline specialised by `overrides` held in `slot`, made there on first use.
    // Used by the techniques' stages.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn cached<'a>(
        slot: &'a std::sync::OnceLock<Self>,
        device: &wgpu::Device,
        overrides: &[(&str, f64)],
    ) -> Result<&'a Self, Error> {
        if slot.get().is_none() {
            let _ = slot.set(Self::with_overrides(device, overrides)?);
        }
        Ok(slot.get().expect("set above"))
    }

    /// Create the pipeline with the stage's typed `override` values (its generated
    /// `Overrides`).
    pub fn with_constants(
        device: &wgpu::Device,
        overrides: &impl Constants,
    ) -> Result<Self, Error> {
        Self::with_overrides(device, &overrides.constants())
    }

    /// Create the pipeline with values for the shader's `override` constants, by name
    /// ([`Self::with_constants`] takes them typed).
    pub fn with_overrides(device: &wgpu::Device, overrides: &[(&str, f64)]) -> Result<Self, Error> {
        Self::with_options(device, overrides, true)
    }

    /// [`Self::with_overrides`], choosing whether wgpu zero-fills workgroup memory before the
    /// shader runs (`false` only for shaders that write every workgroup cell before reading it).
    pub fn with_options(
        device: &wgpu::Device,
        overrides: &[(&str, f64)],
        zero_initialize_workgroup_memory: bool,
    ) -> Result<Self, Error> {
        Self::make(
            device,
            None,
            overrides,
            &[],
            zero_initialize_workgroup_memory,
        )
    }

    /// Create the pipeline with the lengths of the shader's unsized binding arrays
    /// (`binding_array<T>`), given as its generated `ArrayCounts`: the bind group layout holds
    /// them, and `bind` takes exactly that many elements.
    pub fn with_counts(device: &wgpu::Device, counts: &impl Counts) -> Result<Self, Error> {
        Self::make(device, None, &[], &counts.counts(), true)
    }

    /// [`Self::with_counts`] with the stage's typed `override` values too.
    pub fn with_constants_and_counts(
        device: &wgpu::Device,
        overrides: &impl Constants,
        counts: &impl Counts,
    ) -> Result<Self, Error> {
        Self::make(device, None, &overrides.constants(), &counts.counts(), true)
    }

    pub(crate) fn make(
        device: &wgpu::Device,
        relinked: Option<&str>,
        overrides: &[(&str, f64)],
        counts: &[(&str, u32)],
        zero_initialize_workgroup_memory: bool,
    ) -> Result<Self, Error> {
        let info = E::INFO;
        info.check_overrides(overrides)?;
        // Lengths first: a missing one is the caller's to give on any device.
        let slots = info.slots_with(device, counts)?;
        info.check_features(device)?;
        let workgroup_size = check_workgroup_size(device, info, overrides)?;
        crate::gpu::scoped(device, info.stage, || {
            let layouts = info.layouts(device, &slots);
            let pipeline = build_compute(
                device,
                info,
                relinked,
                &layouts,
                overrides,
                zero_initialize_workgroup_memory,
            );
            Self {
                pipeline,
                layouts,
                slots,
                workgroup_size,
                _e: PhantomData,
            }
        })
    }

    /// Check every resource against the shader's slots and make the bind groups.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        bind_groups(device, &self.layouts, &self.slots, resources)
    }

    /// [`Self::bind`], keeping the groups in `kept` for the next call with the same resources
    /// (a per-frame stage's kept buffers and views): no bind group a frame.
    // Used by the techniques' per-frame stages.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn bind_kept(
        &self,
        device: &wgpu::Device,
        kept: &KeptBound<E>,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        kept.get(&self.layouts, resources, || self.bind(device, resources))
    }

    /// Record one dispatch of `groups` workgroups into `pass`.
    pub fn dispatch(&self, pass: &mut wgpu::ComputePass<'_>, bound: &Bound<E>, groups: [u32; 3]) {
        pass.set_pipeline(&self.pipeline);
        bound.set_compute(pass);
        pass.dispatch_workgroups(groups[0], groups[1], groups[2]);
    }

    /// Bind `resources` and record one dispatch of `groups` workgroups in a compute pass of its
    /// own, timed under `name` when `rec` carries a profiler.
    pub fn record(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        resources: &E::Resources<'_>,
        groups: [u32; 3],
        name: &str,
    ) -> Result<(), Error> {
        let bound = self.bind(device, resources)?;
        let mut rec = rec.recorder();
        let mut pass = rec.compute_pass(E::INFO.stage, name);
        self.dispatch(&mut pass, &bound, groups);
        Ok(())
    }

    /// [`Self::record`] binding through `kept` ([`Self::bind_kept`]).
    // Used by the techniques' per-frame stages.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn record_kept(
        &self,
        device: &wgpu::Device,
        rec: &mut impl crate::gpu::Record,
        kept: &KeptBound<E>,
        resources: &E::Resources<'_>,
        groups: [u32; 3],
        name: &str,
    ) -> Result<(), Error> {
        let bound = self.bind_kept(device, kept, resources)?;
        let mut rec = rec.recorder();
        let mut pass = rec.compute_pass(E::INFO.stage, name);
        self.dispatch(&mut pass, &bound, groups);
        Ok(())
    }

    /// Its workgroup size, with the overrides it was made with.
    pub fn workgroup_size(&self) -> [u32; 3] {
        self.workgroup_size
    }

    /// Workgroups needed to cover `extent` invocations on each axis, at the size this pipeline
    /// was made with (an entry sized by overrides: with the values given to it).
    pub fn groups(&self, extent: [u32; 3]) -> [u32; 3] {
        [0, 1, 2].map(|i| extent[i].div_ceil(self.workgroup_size[i].max(1)))
    }

    /// Workgroups needed to cover `extent` invocations on each axis, at the shader's
    /// `@workgroup_size` (an entry sized by overrides: at their defaults; [`Self::groups`] on
    /// a pipeline made with others, or the generated `groups_for(&Overrides, extent)`).
    pub fn groups_for(extent: [u32; 3]) -> [u32; 3] {
        let ws = E::INFO.workgroup_size().unwrap_or([1, 1, 1]);
        [
            extent[0].div_ceil(ws[0]),
            extent[1].div_ceil(ws[1]),
            extent[2].div_ceil(ws[2]),
        ]
    }
}

/// `info`'s workgroup size with `overrides`, refused where the device cannot run it (a size an
/// override sets is checked here, where its value is known).
fn check_workgroup_size(
    device: &wgpu::Device,
    info: &EntryInfo,
    overrides: &[(&str, f64)],
) -> Result<[u32; 3], Error> {
    let size = info.workgroup_size_with(overrides).unwrap_or([1, 1, 1]);
    let l = device.limits();
    let most = [
        l.max_compute_workgroup_size_x,
        l.max_compute_workgroup_size_y,
        l.max_compute_workgroup_size_z,
    ];
    let total = size.iter().map(|&d| d as u64).product::<u64>();
    if size.contains(&0) {
        return Err(Error::invalid(
            info.stage,
            format!("`{}`: workgroup size {size:?} has a zero", info.entry_point),
        ));
    }
    if (0..3).any(|i| size[i] > most[i]) || total > l.max_compute_invocations_per_workgroup as u64 {
        return Err(Error::Unsupported {
            stage: info.stage,
            what: format!(
                "`{}`: workgroup size {size:?} ({total} invocations) is past this device's \
                 limits ({most:?}, {} invocations)",
                info.entry_point, l.max_compute_invocations_per_workgroup
            ),
        });
    }
    Ok(size)
}

/// How a render pipeline draws: the parts the shader cannot say.
#[derive(Debug, Clone, Default)]
pub struct RenderTargets<'a> {
    /// One per fragment output, in location order.
    pub color: &'a [Option<wgpu::ColorTargetState>],
    /// Depth (and stencil) test and write, if the pass has a depth target.
    pub depth_stencil: Option<wgpu::DepthStencilState>,
    /// Topology, culling and polygon mode.
    pub primitive: wgpu::PrimitiveState,
    /// Sample count and mask.
    pub multisample: wgpu::MultisampleState,
}

/// A render pipeline for a generated vertex + fragment entry pair `E`.
pub struct RenderPipeline<E> {
    /// The wgpu pipeline.
    pub pipeline: wgpu::RenderPipeline,
    layouts: Vec<(u32, wgpu::BindGroupLayout)>,
    /// The shader's slots, unsized binding arrays at the lengths the pipeline was made with.
    slots: Vec<Slot>,
    _e: PhantomData<E>,
}

impl<E: Entry> RenderPipeline<E> {
    /// Create the pipeline; colour targets are checked against the fragment outputs first.
    pub fn new(device: &wgpu::Device, targets: &RenderTargets<'_>) -> Result<Self, Error> {
        Self::make(device, None, targets, &[])
    }

    /// [`Self::new`] with the lengths of the shader's unsized binding arrays (see
    /// [`ComputePipeline::with_counts`]).
    pub fn with_counts(
        device: &wgpu::Device,
        targets: &RenderTargets<'_>,
        counts: &impl Counts,
    ) -> Result<Self, Error> {
        Self::make(device, None, targets, &counts.counts())
    }

    pub(crate) fn make(
        device: &wgpu::Device,
        relinked: Option<&str>,
        targets: &RenderTargets<'_>,
        counts: &[(&str, u32)],
    ) -> Result<Self, Error> {
        let info = E::INFO;
        let slots = info.slots_with(device, counts)?;
        info.check_features(device)?;
        let EntryKind::Render {
            targets: outputs, ..
        } = info.kind
        else {
            return Err(Error::Invalid {
                stage: info.stage,
                what: "not a render entry point".into(),
            });
        };
        if targets.color.len() != outputs.len() {
            return Err(Error::Invalid {
                stage: info.stage,
                what: format!(
                    "{} colour targets given, the fragment shader writes {}",
                    targets.color.len(),
                    outputs.len()
                ),
            });
        }
        for (t, o) in targets.color.iter().zip(outputs) {
            let Some(t) = t else { continue };
            let class = match t.format.sample_type(None, None) {
                Some(wgpu::TextureSampleType::Uint) => ScalarClass::Uint,
                Some(wgpu::TextureSampleType::Sint) => ScalarClass::Sint,
                _ => ScalarClass::Float,
            };
            if class != o.scalar {
                return Err(Error::Invalid {
                    stage: info.stage,
                    what: format!(
                        "target @location({}) has format {:?}, the shader writes {:?} values",
                        o.location, t.format, o.scalar
                    ),
                });
            }
        }
        let formats: Vec<wgpu::TextureFormat> =
            targets.color.iter().flatten().map(|t| t.format).collect();
        crate::gpu::check_target_bytes(device, info.stage, &formats)?;
        crate::gpu::scoped(device, info.stage, || {
            let layouts = info.layouts(device, &slots);
            let pipeline = build_render(device, info, relinked, &layouts, targets);
            Self {
                pipeline,
                layouts,
                slots,
                _e: PhantomData,
            }
        })
    }

    /// Check every resource against the shader's slots and make the bind groups.
    pub fn bind(
        &self,
        device: &wgpu::Device,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        bind_groups(device, &self.layouts, &self.slots, resources)
    }

    /// [`Self::bind`], keeping the groups in `kept` (see [`ComputePipeline::bind_kept`]).
    // Used by the techniques' per-frame stages.
    #[cfg_attr(not(feature = "techniques"), allow(dead_code))]
    pub(crate) fn bind_kept(
        &self,
        device: &wgpu::Device,
        kept: &KeptBound<E>,
        resources: &E::Resources<'_>,
    ) -> Result<Bound<E>, Error> {
        kept.get(&self.layouts, resources, || self.bind(device, resources))
    }
}

pub(crate) fn build_compute(
    device: &wgpu::Device,
    info: &EntryInfo,
    relinked: Option<&str>,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    overrides: &[(&str, f64)],
    zero_initialize_workgroup_memory: bool,
) -> wgpu::ComputePipeline {
    let layout = info.pipeline_layout(device, layouts);
    device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(info.stage),
        layout: Some(&layout),
        module: &module(device, info, relinked),
        entry_point: Some(info.entry_point),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: overrides,
            zero_initialize_workgroup_memory,
        },
        cache: crate::gpu::installed_pipeline_cache(device).as_ref(),
    })
}

/// Build a render pipeline; `info.kind` must be `Render` (checked by the callers).
pub(crate) fn build_render(
    device: &wgpu::Device,
    info: &EntryInfo,
    relinked: Option<&str>,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    targets: &RenderTargets<'_>,
) -> wgpu::RenderPipeline {
    let EntryKind::Render {
        vertex,
        vertex_source,
        vertex_buffers,
        ..
    } = info.kind
    else {
        unreachable!("callers pass render entries")
    };
    let layout = info.pipeline_layout(device, layouts);
    let module = module(device, info, relinked);
    // A vertex entry of another file: its own stage's module (never relinked: a reload
    // relinks the fragment entry's file).
    let vertex_module =
        vertex_source.map(|source| self::module(device, &EntryInfo { source, ..*info }, None));
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(info.stage),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module: vertex_module.as_ref().unwrap_or(&module),
            entry_point: Some(vertex),
            compilation_options: Default::default(),
            buffers: vertex_buffers,
        },
        // A depth-only pipeline is named after its vertex entry and has no fragment stage.
        fragment: (info.entry_point != vertex).then(|| wgpu::FragmentState {
            module: &module,
            entry_point: Some(info.entry_point),
            compilation_options: Default::default(),
            targets: targets.color,
        }),
        primitive: targets.primitive,
        depth_stencil: targets.depth_stencil.clone(),
        multisample: targets.multisample,
        multiview_mask: None,
        cache: crate::gpu::installed_pipeline_cache(device).as_ref(),
    })
}

/// Create the pipeline for any entry point from its table alone (used to prove every generated
/// pipeline is accepted by wgpu, on the noop backend in tests). Colour targets get a format of
/// each output's scalar class, and a depth target.
pub fn create_any(device: &wgpu::Device, info: &'static EntryInfo) -> Result<(), Error> {
    info.check_features(device)?;
    // An unsized binding array at length 1.
    let ones: Vec<(&str, u32)> = info
        .slots
        .iter()
        .filter(|s| s.unsized_array)
        .map(|s| (s.name, 1))
        .collect();
    let slots = info.slots_with(device, &ones)?;
    crate::gpu::scoped(device, info.stage, || {
        let layouts = info.layouts(device, &slots);
        match info.kind {
            EntryKind::Compute { .. } => {
                let _ = build_compute(device, info, None, &layouts, &[], true);
            }
            EntryKind::Render { targets, .. } => {
                let color: Vec<_> = targets
                    .iter()
                    .map(|t| {
                        Some(wgpu::ColorTargetState::from(match t.scalar {
                            ScalarClass::Float => wgpu::TextureFormat::Rgba8Unorm,
                            ScalarClass::Uint => wgpu::TextureFormat::R32Uint,
                            ScalarClass::Sint => wgpu::TextureFormat::R32Sint,
                        }))
                    })
                    .collect();
                let _ = build_render(
                    device,
                    info,
                    None,
                    &layouts,
                    &RenderTargets {
                        color: &color,
                        // A depth target, so stages that write `frag_depth` are accepted too.
                        depth_stencil: Some(wgpu::DepthStencilState {
                            format: wgpu::TextureFormat::Depth32Float,
                            depth_write_enabled: Some(true),
                            depth_compare: Some(wgpu::CompareFunction::Always),
                            stencil: Default::default(),
                            bias: Default::default(),
                        }),
                        ..Default::default()
                    },
                );
            }
        }
    })
}
