//! Bind groups: checked resources made into groups, bound with their dynamic offsets.

use super::*;

use super::check::check;

/// fieldkit's own checks of every resource (kind, format, size, usage, sample type), then the
/// bind groups. No error scope: binding never waits on the device.
pub(crate) fn bind_groups<E: Entry>(
    device: &wgpu::Device,
    layouts: &[(u32, wgpu::BindGroupLayout)],
    slots: &[Slot],
    resources: &E::Resources<'_>,
) -> Result<Bound<E>, Error> {
    let info = E::INFO;
    let res = E::resources(resources);
    let shared = E::groups(resources);
    // The slots bound one by one: all but the shared groups', in the order `res` lists them.
    let own: Vec<Slot> = slots
        .iter()
        .filter(|s| !info.shared_groups.contains(&s.group))
        .copied()
        .collect();
    let mut groups = Vec::new();
    for (g, layout) in layouts {
        let dynamic = info
            .slots
            .iter()
            .filter(|s| s.group == *g && has_dynamic_offset(s))
            .count();
        if let Some((_, group)) = shared.iter().find(|(sg, _)| sg == g) {
            groups.push((*g, (*group).clone(), dynamic));
            continue;
        }
        let (slots, group_res): (Vec<Slot>, Vec<&Resource<'_>>) = own
            .iter()
            .zip(&res)
            .filter(|(s, _)| s.group == *g)
            .map(|(s, r)| (*s, r))
            .unzip();
        let group = make_group_refs(
            device,
            layout,
            &slots,
            &group_res,
            info.stage,
            info.entry_point,
            *g,
        )?;
        groups.push((*g, group, dynamic));
    }
    Ok(Bound {
        groups,
        stage: info.stage,
        _e: PhantomData,
    })
}

/// Check each resource against its slot, then make group `g` of them.
pub(crate) fn make_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    res: &[Resource<'_>],
    stage: &'static str,
    entry_point: &'static str,
    g: u32,
) -> Result<wgpu::BindGroup, Error> {
    let refs: Vec<&Resource<'_>> = res.iter().collect();
    make_group_refs(device, layout, slots, &refs, stage, entry_point, g)
}

pub(crate) fn make_group_refs(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    slots: &[Slot],
    res: &[&Resource<'_>],
    stage: &'static str,
    entry_point: &'static str,
    g: u32,
) -> Result<wgpu::BindGroup, Error> {
    for (slot, r) in slots.iter().zip(res) {
        check(slot, r, device).map_err(|problem| {
            Error::Binding(BindingError {
                stage,
                entry_point,
                binding: slot.name,
                group: slot.group,
                index: slot.binding,
                problem,
            })
        })?;
    }
    let entries: Vec<wgpu::BindGroupEntry> = slots
        .iter()
        .zip(res)
        .map(|(s, r)| wgpu::BindGroupEntry {
            binding: s.binding,
            resource: match r {
                Resource::Buffer(b) => wgpu::BindingResource::Buffer(b.clone()),
                Resource::Texture(v) | Resource::StorageTexture(v) => {
                    wgpu::BindingResource::TextureView(v)
                }
                Resource::Sampler(s) => wgpu::BindingResource::Sampler(s),
                Resource::Buffers(b) => wgpu::BindingResource::BufferArray(b),
                Resource::Textures(v) | Resource::StorageTextures(v) => {
                    wgpu::BindingResource::TextureViewArray(v)
                }
                Resource::Samplers(s) => wgpu::BindingResource::SamplerArray(s),
            },
        })
        .collect();
    let label = format!("{stage}::{entry_point} group {g}");
    Ok(device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(&label),
        layout,
        entries: &entries,
    }))
}

/// Offset 0 for each of `n` dynamic bindings, without an allocation per pass where `n` is
/// within what any adapter offers (WebGPU's defaults: 8 uniform and 4 storage per layout).
pub(crate) fn zero_offsets(n: usize) -> std::borrow::Cow<'static, [u32]> {
    const ZEROS: [u32; 64] = [0; 64];
    match ZEROS.get(..n) {
        Some(z) => std::borrow::Cow::Borrowed(z),
        None => std::borrow::Cow::Owned(vec![0; n]),
    }
}

/// A bind group's index, the group, and its dynamic offsets.
pub(crate) type GroupOffsets<'s, 'o> = (u32, &'s wgpu::BindGroup, &'o [u32]);

pub(crate) fn has_dynamic_offset(slot: &Slot) -> bool {
    matches!(
        slot.ty,
        wgpu::BindingType::Buffer {
            has_dynamic_offset: true,
            ..
        }
    )
}

/// The bind groups one call site made last and the resources they hold, so that a stage bound
/// to the same resources every frame (its kept buffers and views) makes its groups once: see
/// [`ComputePipeline::bind_kept`]. Resources compare by identity (wgpu's handles are equal
/// only to clones of themselves), and the key holds clones, so an identity is never reused
/// while it is kept; it is replaced, freeing the old groups, when other resources come.
// Used by the techniques' per-frame stages.
#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
pub(crate) struct KeptBound<E> {
    /// The layouts (a variant of the pipeline may have others) and resources, and the groups.
    kept: std::sync::Mutex<Option<KeptGroups<E>>>,
}

impl<E> Default for KeptBound<E> {
    fn default() -> Self {
        Self {
            kept: Default::default(),
        }
    }
}

type KeptGroups<E> = (Vec<wgpu::BindGroupLayout>, Vec<ResourceKey>, Bound<E>);

/// A resource by identity, holding a clone of it (see [`KeptBound`]).
#[derive(PartialEq)]
enum ResourceKey {
    Buffer(wgpu::Buffer, u64, Option<std::num::NonZeroU64>),
    View(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

impl ResourceKey {
    /// The key of `r`; `None` for binding arrays (never kept).
    fn of(r: &Resource<'_>) -> Option<Self> {
        Some(match r {
            Resource::Buffer(b) => ResourceKey::Buffer(b.buffer.clone(), b.offset, b.size),
            Resource::Texture(v) | Resource::StorageTexture(v) => ResourceKey::View((*v).clone()),
            Resource::Sampler(s) => ResourceKey::Sampler((*s).clone()),
            _ => return None,
        })
    }
}

#[cfg_attr(not(feature = "techniques"), allow(dead_code))]
impl<E: Entry> KeptBound<E> {
    /// The groups kept for `resources` where they are the same as last time, else `make`'s,
    /// kept for next time. Shared groups are keyed too (their groups by identity).
    pub(crate) fn get(
        &self,
        layouts: &[(u32, wgpu::BindGroupLayout)],
        resources: &E::Resources<'_>,
        make: impl FnOnce() -> Result<Bound<E>, Error>,
    ) -> Result<Bound<E>, Error> {
        let keys: Option<Vec<ResourceKey>> = E::resources(resources)
            .iter()
            .map(ResourceKey::of)
            .collect();
        let shared: Vec<wgpu::BindGroup> = E::groups(resources)
            .iter()
            .map(|(_, g)| (*g).clone())
            .collect();
        let Some(keys) = keys else {
            return make();
        };
        let layouts: Vec<wgpu::BindGroupLayout> = layouts.iter().map(|(_, l)| l.clone()).collect();
        let mut kept = self.kept.lock().unwrap_or_else(|e| e.into_inner());
        if let Some((l, k, bound)) = kept.as_ref()
            && *l == layouts
            && *k == keys
            && bound.shared_are(&shared)
        {
            return Ok(bound.clone());
        }
        let bound = make()?;
        *kept = Some((layouts, keys, bound.clone()));
        Ok(bound)
    }
}

/// Bind groups for one dispatch or draw, made by [`ComputePipeline::bind`] / [`RenderPipeline::bind`].
pub struct Bound<E> {
    /// Each group, and how many of its bindings take a dynamic offset.
    groups: Vec<(u32, wgpu::BindGroup, usize)>,
    stage: &'static str,
    _e: PhantomData<E>,
}

impl<E> Clone for Bound<E> {
    fn clone(&self) -> Self {
        Self {
            groups: self.groups.clone(),
            stage: self.stage,
            _e: PhantomData,
        }
    }
}

impl<E: Entry> Bound<E> {
    /// Whether the shared groups among these are `shared` (by identity).
    fn shared_are(&self, shared: &[wgpu::BindGroup]) -> bool {
        shared
            .iter()
            .all(|s| self.groups.iter().any(|(_, g, _)| g == s))
    }

    /// Set every bind group on a compute pass (a binding with a dynamic offset at offset 0).
    pub fn set_compute(&self, pass: &mut wgpu::ComputePass<'_>) {
        for (g, group, dynamic) in &self.groups {
            pass.set_bind_group(*g, group, &zero_offsets(*dynamic));
        }
    }
    /// Set every bind group on a render pass (a binding with a dynamic offset at offset 0).
    pub fn set_render(&self, pass: &mut wgpu::RenderPass<'_>) {
        for (g, group, dynamic) in &self.groups {
            pass.set_bind_group(*g, group, &zero_offsets(*dynamic));
        }
    }

    /// Bindings that take a dynamic offset (`fieldkit_build::Builder::dynamic_offset`), in
    /// group then binding order: one offset each is expected.
    pub fn dynamic_offsets(&self) -> usize {
        self.groups.iter().map(|(_, _, d)| d).sum()
    }

    /// [`Self::set_compute`] with `offsets`, one per binding that takes a dynamic offset, in
    /// group then binding order; [`Error::Invalid`] for the wrong number of them.
    pub fn set_compute_with_offsets(
        &self,
        pass: &mut wgpu::ComputePass<'_>,
        offsets: &[u32],
    ) -> Result<(), Error> {
        for (g, group, split) in self.split(offsets)? {
            pass.set_bind_group(g, group, split);
        }
        Ok(())
    }

    /// [`Self::set_render`] with `offsets`, as [`Self::set_compute_with_offsets`] takes them.
    pub fn set_render_with_offsets(
        &self,
        pass: &mut wgpu::RenderPass<'_>,
        offsets: &[u32],
    ) -> Result<(), Error> {
        for (g, group, split) in self.split(offsets)? {
            pass.set_bind_group(g, group, split);
        }
        Ok(())
    }

    /// Each group with its share of `offsets`.
    fn split<'s, 'o>(&'s self, offsets: &'o [u32]) -> Result<Vec<GroupOffsets<'s, 'o>>, Error> {
        if offsets.len() != self.dynamic_offsets() {
            return Err(Error::Invalid {
                stage: self.stage,
                what: format!(
                    "{} dynamic offsets given, the pipeline's layouts take {}",
                    offsets.len(),
                    self.dynamic_offsets()
                ),
            });
        }
        let mut rest = offsets;
        Ok(self
            .groups
            .iter()
            .map(|(g, group, d)| {
                let (mine, after) = rest.split_at(*d);
                rest = after;
                (*g, group, mine)
            })
            .collect())
    }
}
