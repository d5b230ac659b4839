//! fieldkit's own checks of a resource against the slot the shader declares.

use super::*;

pub(crate) fn view_dimension_of(t: &wgpu::Texture) -> wgpu::TextureViewDimension {
    match t.dimension() {
        wgpu::TextureDimension::D1 => wgpu::TextureViewDimension::D1,
        wgpu::TextureDimension::D2 if t.depth_or_array_layers() > 1 => {
            wgpu::TextureViewDimension::D2Array
        }
        wgpu::TextureDimension::D2 => wgpu::TextureViewDimension::D2,
        wgpu::TextureDimension::D3 => wgpu::TextureViewDimension::D3,
    }
}

/// Whether some view of `t` can have dimension `want`: a 2D texture's views are 2D arrays at
/// any layer count (one layer included), 2D with one layer, cubes with six.
pub(crate) fn view_fits(t: &wgpu::Texture, want: wgpu::TextureViewDimension) -> bool {
    use wgpu::TextureViewDimension as V;
    let layers = t.depth_or_array_layers();
    match (t.dimension(), want) {
        (wgpu::TextureDimension::D2, V::D2Array) => true,
        (wgpu::TextureDimension::D2, V::Cube) => layers == 6,
        (wgpu::TextureDimension::D2, V::CubeArray) => layers.is_multiple_of(6),
        _ => view_dimension_of(t) == want,
    }
}

/// Check one resource against its slot. `Err(problem)` says what is wrong, in words. A
/// binding array takes exactly its count of elements, each checked as a single resource.
pub(crate) fn check(slot: &Slot, res: &Resource<'_>, device: &wgpu::Device) -> Result<(), String> {
    let elements: Option<Vec<Resource<'_>>> = match res {
        Resource::Buffers(b) => Some(b.iter().cloned().map(Resource::Buffer).collect()),
        Resource::Textures(v) => Some(v.iter().map(|v| Resource::Texture(v)).collect()),
        Resource::StorageTextures(v) => {
            Some(v.iter().map(|v| Resource::StorageTexture(v)).collect())
        }
        Resource::Samplers(v) => Some(v.iter().map(|v| Resource::Sampler(v)).collect()),
        _ => None,
    };
    match (slot.count, elements) {
        (None, None) => check_one(slot, res, device),
        (Some(count), Some(elements)) => {
            if elements.len() != count.get() as usize {
                let holds = if slot.unsized_array {
                    "the pipeline was made with a length of"
                } else {
                    "holds"
                };
                return Err(format!(
                    "{} resources bound, the shader's `{}` {holds} {count}",
                    elements.len(),
                    slot.wgsl
                ));
            }
            for (i, e) in elements.iter().enumerate() {
                check_one(slot, e, device).map_err(|p| format!("element {i}: {p}"))?;
            }
            Ok(())
        }
        (Some(_), None) => Err(format!(
            "one resource bound, the shader's `{}` is a binding array",
            slot.wgsl
        )),
        (None, Some(_)) => Err(format!(
            "a binding array bound, the shader's `{}` is one resource",
            slot.wgsl
        )),
    }
}

/// [`check`] for a single resource.
pub(crate) fn check_one(
    slot: &Slot,
    res: &Resource<'_>,
    device: &wgpu::Device,
) -> Result<(), String> {
    use wgpu::BindingType as B;
    match (&slot.ty, res) {
        (
            B::Buffer {
                ty,
                min_binding_size,
                ..
            },
            Resource::Buffer(b),
        ) => check_buffer(slot, *ty, *min_binding_size, b, device),
        (
            B::Texture {
                sample_type,
                view_dimension,
                multisampled,
            },
            Resource::Texture(v),
        ) => check_texture(
            slot,
            *sample_type,
            *view_dimension,
            *multisampled,
            v,
            device,
        ),
        (
            B::StorageTexture {
                format,
                view_dimension,
                ..
            },
            Resource::StorageTexture(v),
        ) => check_storage_texture(slot, *format, *view_dimension, v),
        (B::Sampler(_), Resource::Sampler(_)) => Ok(()),
        _ => Err(format!("wrong kind of resource for `{}`", slot.wgsl)),
    }
}

/// A buffer for a uniform or storage slot: its usage, offset alignment, and size against the
/// shader's minimum and the device's binding limit.
pub(crate) fn check_buffer(
    slot: &Slot,
    ty: wgpu::BufferBindingType,
    min_binding_size: Option<wgpu::BufferSize>,
    b: &wgpu::BufferBinding<'_>,
    device: &wgpu::Device,
) -> Result<(), String> {
    let (usage, align, what) = match ty {
        wgpu::BufferBindingType::Uniform => (
            wgpu::BufferUsages::UNIFORM,
            device.limits().min_uniform_buffer_offset_alignment,
            "UNIFORM",
        ),
        _ => (
            wgpu::BufferUsages::STORAGE,
            device.limits().min_storage_buffer_offset_alignment,
            "STORAGE",
        ),
    };
    if !b.buffer.usage().contains(usage) {
        return Err(format!(
            "buffer lacks {what} usage (has {:?})",
            b.buffer.usage()
        ));
    }
    if !b.offset.is_multiple_of(align as u64) {
        return Err(format!("offset {} is not a multiple of {align}", b.offset));
    }
    let size = b
        .size
        .map(|s| s.get())
        .unwrap_or(b.buffer.size().saturating_sub(b.offset));
    if let Some(min) = min_binding_size
        && size < min.get()
    {
        return Err(format!(
            "{size} bytes bound, the shader's `{}` needs at least {}",
            slot.wgsl,
            min.get()
        ));
    }
    // wgpu would reject the bind group with a validation error (a panic in an app
    // without an error handler): say which binding and which limit instead.
    let (max, limit) = match ty {
        wgpu::BufferBindingType::Uniform => (
            device.limits().max_uniform_buffer_binding_size,
            "max_uniform_buffer_binding_size",
        ),
        _ => (
            device.limits().max_storage_buffer_binding_size,
            "max_storage_buffer_binding_size",
        ),
    };
    if size > max {
        return Err(format!(
            "{size} bytes bound, more than the device's {limit} ({max})"
        ));
    }
    Ok(())
}

/// A sampled texture: its usage, view dimension, sample count and sample type.
pub(crate) fn check_texture(
    slot: &Slot,
    sample_type: wgpu::TextureSampleType,
    view_dimension: wgpu::TextureViewDimension,
    multisampled: bool,
    v: &wgpu::TextureView,
    device: &wgpu::Device,
) -> Result<(), String> {
    let t = v.texture();
    if !t.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        return Err(format!(
            "texture lacks TEXTURE_BINDING usage (has {:?})",
            t.usage()
        ));
    }
    if !view_fits(t, view_dimension) {
        return Err(format!(
            "{:?} texture bound, the shader reads `{}`",
            view_dimension_of(t),
            slot.wgsl
        ));
    }
    if (t.sample_count() > 1) != multisampled {
        return Err(format!(
            "sample count {} does not suit `{}`",
            t.sample_count(),
            slot.wgsl
        ));
    }
    let features = device.features();
    let fits = |have: Option<wgpu::TextureSampleType>| match (sample_type, have) {
        (
            wgpu::TextureSampleType::Float { filterable: true },
            Some(wgpu::TextureSampleType::Float { filterable }),
        ) => filterable,
        // Depth formats may be read as unfilterable float (textureLoad).
        (
            wgpu::TextureSampleType::Float { filterable: false },
            Some(wgpu::TextureSampleType::Float { .. } | wgpu::TextureSampleType::Depth),
        ) => true,
        (want, Some(h)) => want == h,
        (_, None) => false,
    };
    // A combined depth-stencil format is read through a view of one aspect (the view
    // does not say which): either aspect may fit.
    let ok = match t.format().sample_type(None, Some(features)) {
        Some(have) => fits(Some(have)),
        None => [
            wgpu::TextureAspect::DepthOnly,
            wgpu::TextureAspect::StencilOnly,
        ]
        .into_iter()
        .any(|a| fits(t.format().sample_type(Some(a), Some(features)))),
    };
    if !ok {
        return Err(format!(
            "texture format {:?} cannot be read as `{}` (needs {:?})",
            t.format(),
            slot.wgsl,
            sample_type
        ));
    }
    Ok(())
}

/// A storage texture: its usage, format and view dimension.
pub(crate) fn check_storage_texture(
    slot: &Slot,
    format: wgpu::TextureFormat,
    view_dimension: wgpu::TextureViewDimension,
    v: &wgpu::TextureView,
) -> Result<(), String> {
    let t = v.texture();
    if !t.usage().contains(wgpu::TextureUsages::STORAGE_BINDING) {
        return Err(format!(
            "texture lacks STORAGE_BINDING usage (has {:?})",
            t.usage()
        ));
    }
    if t.format() != format {
        return Err(format!(
            "texture format {:?} bound, the shader's `{}` needs {:?}",
            t.format(),
            slot.wgsl,
            format
        ));
    }
    if !view_fits(t, view_dimension) {
        return Err(format!(
            "{:?} texture bound, the shader writes `{}`",
            view_dimension_of(t),
            slot.wgsl
        ));
    }
    Ok(())
}
