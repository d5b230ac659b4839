//! `cargo xtask shader-stats`: what the Vulkan driver made of each compute entry point
//! (registers, spills, shared memory, instruction counts: whatever the driver reports), through
//! `VK_KHR_pipeline_executable_properties`. wgpu does not expose that extension, so this opens
//! its own Vulkan device with `ash` (the crate wgpu's Vulkan backend is built on) and builds
//! each entry point from naga's SPIR-V with a pipeline layout read off the module's bindings.
//! The stages are the linked WGSL built into this binary, what its benches run (`--checkout`:
//! the shader files of the checkout instead), so two builds sent to a GPU machine each report
//! their own.
//!
//! For performance work: a kernel that is slow for its arithmetic is often short of registers
//! (few warps in flight) or spilling to local memory, which only the driver can say.

use std::ffi::CStr;
use std::path::Path;
use std::process::ExitCode;

use ash::vk;

/// Where the stages come from: the linked WGSL built into this binary (`fieldkit::shaders::ALL`,
/// what its benches ran), or the shader files of a checkout (validated afresh).
pub enum Source<'a> {
    Built,
    Checkout(&'a Path),
}

pub fn run(source: Source, filter: Option<&str>, overrides: &[String], checks: &str) -> ExitCode {
    match stats(source, filter, overrides, checks) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("shader-stats: {e}");
            ExitCode::FAILURE
        }
    }
}

/// `NAME=value` pairs for the stages' `override` constants.
fn parse_overrides(list: &[String]) -> Result<Vec<(String, f64)>, String> {
    list.iter()
        .map(|s| {
            let (k, v) = s
                .split_once('=')
                .ok_or_else(|| format!("override {s:?} is not NAME=value"))?;
            let v: f64 = match v {
                "true" => 1.0,
                "false" => 0.0,
                _ => v
                    .parse()
                    .map_err(|_| format!("override {s:?}: {v:?} is not a number"))?,
            };
            Ok((k.to_string(), v))
        })
        .collect()
}

/// One executable of a pipeline (a compute pipeline has one): its name and its statistics.
type Executable = (String, Vec<(String, String)>);

struct Vulkan {
    _entry: ash::Entry,
    instance: ash::Instance,
    device: ash::Device,
    executables: ash::khr::pipeline_executable_properties::Device,
    name: String,
}

impl Vulkan {
    fn open() -> Result<Self, String> {
        // SAFETY: loading the system's Vulkan loader; every handle made below is destroyed in
        // `Drop` before the loader goes.
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| format!("no Vulkan loader ({e}); install mesa-vulkan-drivers"))?;
        let app = vk::ApplicationInfo::default()
            .application_name(c"fieldkit shader-stats")
            .api_version(vk::API_VERSION_1_2);
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default().application_info(&app),
                None,
            )
        }
        .map_err(|e| format!("vkCreateInstance: {e}"))?;
        let ext = ash::khr::pipeline_executable_properties::NAME;
        let devices = unsafe { instance.enumerate_physical_devices() }
            .map_err(|e| format!("vkEnumeratePhysicalDevices: {e}"))?;
        // A discrete GPU first, as wgpu's default adapter would be; only one with the extension.
        let mut candidates: Vec<(vk::PhysicalDevice, vk::PhysicalDeviceProperties)> = devices
            .into_iter()
            .map(|d| (d, unsafe { instance.get_physical_device_properties(d) }))
            .filter(|(d, _)| {
                unsafe { instance.enumerate_device_extension_properties(*d) }
                    .unwrap_or_default()
                    .iter()
                    .any(|e| e.extension_name_as_c_str() == Ok(ext))
            })
            .collect();
        candidates.sort_by_key(|(_, p)| p.device_type != vk::PhysicalDeviceType::DISCRETE_GPU);
        let Some(&(physical, props)) = candidates.first() else {
            unsafe { instance.destroy_instance(None) };
            return Err(format!("no Vulkan device offers {}", ext.to_string_lossy()));
        };
        let name = props
            .device_name_as_c_str()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let family = unsafe { instance.get_physical_device_queue_family_properties(physical) }
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or("the device has no compute queue")? as u32;
        let priorities = [1.0];
        let queues = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(family)
            .queue_priorities(&priorities)];
        let exts = [ext.as_ptr()];
        let mut feature = vk::PhysicalDevicePipelineExecutablePropertiesFeaturesKHR::default()
            .pipeline_executable_info(true);
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queues)
            .enabled_extension_names(&exts)
            .push_next(&mut feature);
        let device = unsafe { instance.create_device(physical, &info, None) }
            .map_err(|e| format!("vkCreateDevice: {e}"))?;
        let executables = ash::khr::pipeline_executable_properties::Device::new(&instance, &device);
        Ok(Self {
            _entry: entry,
            instance,
            device,
            executables,
            name,
        })
    }

    /// (executable name, [(statistic, value)]) for one compute entry point.
    fn compute_stats(
        &self,
        spirv: &[u32],
        entry: &str,
        bindings: &[(u32, u32, vk::DescriptorType)],
    ) -> Result<Vec<Executable>, String> {
        let d = &self.device;
        let sets = bindings.iter().map(|b| b.0 + 1).max().unwrap_or(0);
        let mut layouts = Vec::new();
        for set in 0..sets {
            let entries: Vec<vk::DescriptorSetLayoutBinding> = bindings
                .iter()
                .filter(|b| b.0 == set)
                .map(|&(_, binding, ty)| {
                    vk::DescriptorSetLayoutBinding::default()
                        .binding(binding)
                        .descriptor_type(ty)
                        .descriptor_count(1)
                        .stage_flags(vk::ShaderStageFlags::COMPUTE)
                })
                .collect();
            let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&entries);
            layouts.push(
                unsafe { d.create_descriptor_set_layout(&info, None) }
                    .map_err(|e| format!("vkCreateDescriptorSetLayout: {e}"))?,
            );
        }
        let cleanup = |layouts: &[vk::DescriptorSetLayout]| {
            for &l in layouts {
                unsafe { d.destroy_descriptor_set_layout(l, None) };
            }
        };
        let pipeline_layout = match unsafe {
            d.create_pipeline_layout(
                &vk::PipelineLayoutCreateInfo::default().set_layouts(&layouts),
                None,
            )
        } {
            Ok(l) => l,
            Err(e) => {
                cleanup(&layouts);
                return Err(format!("vkCreatePipelineLayout: {e}"));
            }
        };
        let module = unsafe {
            d.create_shader_module(&vk::ShaderModuleCreateInfo::default().code(spirv), None)
        }
        .map_err(|e| format!("vkCreateShaderModule: {e}"))?;
        let name = std::ffi::CString::new(entry).map_err(|e| e.to_string())?;
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module)
            .name(&name);
        let info = vk::ComputePipelineCreateInfo::default()
            .flags(vk::PipelineCreateFlags::CAPTURE_STATISTICS_KHR)
            .stage(stage)
            .layout(pipeline_layout);
        let made = unsafe { d.create_compute_pipelines(vk::PipelineCache::null(), &[info], None) };
        let result = match made {
            Ok(p) => {
                let out = self.read(p[0]);
                unsafe { d.destroy_pipeline(p[0], None) };
                out
            }
            Err((_, e)) => Err(format!("vkCreateComputePipelines: {e}")),
        };
        unsafe {
            d.destroy_shader_module(module, None);
            d.destroy_pipeline_layout(pipeline_layout, None);
        }
        cleanup(&layouts);
        result
    }

    fn read(&self, pipeline: vk::Pipeline) -> Result<Vec<Executable>, String> {
        let props = unsafe {
            self.executables.get_pipeline_executable_properties(
                &vk::PipelineInfoKHR::default().pipeline(pipeline),
            )
        }
        .map_err(|e| format!("vkGetPipelineExecutablePropertiesKHR: {e}"))?;
        let mut out = Vec::new();
        for (i, p) in props.iter().enumerate() {
            let stats = unsafe {
                self.executables.get_pipeline_executable_statistics(
                    &vk::PipelineExecutableInfoKHR::default()
                        .pipeline(pipeline)
                        .executable_index(i as u32),
                )
            }
            .map_err(|e| format!("vkGetPipelineExecutableStatisticsKHR: {e}"))?;
            let text = |c: Result<&CStr, _>| {
                c.map(|s: &CStr| s.to_string_lossy().into_owned())
                    .unwrap_or_default()
            };
            let values = stats
                .iter()
                .map(|s| {
                    // SAFETY: the union member read is the one `format` names.
                    let v = unsafe {
                        match s.format {
                            vk::PipelineExecutableStatisticFormatKHR::BOOL32 => {
                                (s.value.b32 != 0).to_string()
                            }
                            vk::PipelineExecutableStatisticFormatKHR::INT64 => {
                                s.value.i64.to_string()
                            }
                            vk::PipelineExecutableStatisticFormatKHR::UINT64 => {
                                s.value.u64.to_string()
                            }
                            _ => format!("{:.3}", s.value.f64),
                        }
                    };
                    (text(s.name_as_c_str()), v)
                })
                .collect();
            out.push((text(p.name_as_c_str()), values));
        }
        Ok(out)
    }
}

impl Drop for Vulkan {
    fn drop(&mut self) {
        unsafe {
            self.device.destroy_device(None);
            self.instance.destroy_instance(None);
        }
    }
}

/// Descriptor (set, binding, type) of every bound global of `module`.
fn bindings(module: &naga::Module) -> Vec<(u32, u32, vk::DescriptorType)> {
    module
        .global_variables
        .iter()
        .filter_map(|(_, g)| {
            let b = g.binding.as_ref()?;
            let ty = match g.space {
                naga::AddressSpace::Uniform => vk::DescriptorType::UNIFORM_BUFFER,
                naga::AddressSpace::Storage { .. } => vk::DescriptorType::STORAGE_BUFFER,
                naga::AddressSpace::Handle => match &module.types[g.ty].inner {
                    naga::TypeInner::Image {
                        class: naga::ImageClass::Storage { .. },
                        ..
                    } => vk::DescriptorType::STORAGE_IMAGE,
                    naga::TypeInner::Image { .. } => vk::DescriptorType::SAMPLED_IMAGE,
                    naga::TypeInner::Sampler { .. } => vk::DescriptorType::SAMPLER,
                    _ => return None,
                },
                _ => return None,
            };
            Some((b.group, b.binding, ty))
        })
        .collect()
}

/// naga's SPIR-V options for `--checks`: `wgpu` as wgpu's Vulkan backend sets them on a
/// device with robust buffer and image access (indices clamped, buffers and images left to the
/// driver, every loop bounded), `no-loop-bounding`, `none` (what
/// `create_shader_module_trusted` with every check off gives).
fn spirv_options(checks: &str) -> Result<naga::back::spv::Options<'static>, String> {
    use naga::proc::{BoundsCheckPolicies, BoundsCheckPolicy::*};
    let wgpu = BoundsCheckPolicies {
        index: Restrict,
        buffer: Unchecked,
        image_load: Unchecked,
        binding_array: Unchecked,
    };
    let (policies, bounded) = match checks {
        "wgpu" => (wgpu, true),
        "no-loop-bounding" => (wgpu, false),
        "none" => (BoundsCheckPolicies::default(), false),
        _ => {
            return Err(format!(
                "--checks {checks:?}: one of wgpu, no-loop-bounding, none"
            ));
        }
    };
    Ok(naga::back::spv::Options {
        lang_version: (1, 3),
        bounds_check_policies: policies,
        force_loop_bounding: bounded,
        ..Default::default()
    })
}

/// One stage's module: its `room::stage` name, the module and its validation.
struct Stage {
    id: String,
    module: naga::Module,
    info: naga::valid::ModuleInfo,
}

/// The stages as `source` has them.
fn stages_of(source: Source) -> Result<Vec<Stage>, String> {
    match source {
        Source::Checkout(root) => Ok(crate::stages(root)
            .ok_or("the shaders do not build")?
            .into_iter()
            .map(|s| Stage {
                id: s.file.id(),
                module: s.module,
                info: s.info,
            })
            .collect()),
        Source::Built => {
            // One linked source per stage (every entry point of a stage shares it).
            let sources: std::collections::BTreeMap<&str, &str> = fieldkit::shaders::ALL
                .iter()
                .map(|e| (e.stage, e.source))
                .collect();
            sources
                .into_iter()
                .map(|(id, text)| {
                    let module = naga::front::wgsl::parse_str(text)
                        .map_err(|e| format!("{id}: {}", e.emit_to_string(text)))?;
                    let info = naga::valid::Validator::new(
                        naga::valid::ValidationFlags::all(),
                        naga::valid::Capabilities::all(),
                    )
                    .validate(&module)
                    .map_err(|e| format!("{id}: {e}"))?;
                    Ok(Stage {
                        id: id.to_string(),
                        module,
                        info,
                    })
                })
                .collect()
        }
    }
}

fn stats(
    source: Source,
    filter: Option<&str>,
    overrides: &[String],
    checks: &str,
) -> Result<(), String> {
    let overrides = parse_overrides(overrides)?;
    let options = spirv_options(checks)?;
    let stages = stages_of(source)?;
    let vulkan = Vulkan::open()?;
    println!("device: {}", vulkan.name);
    for stage in &stages {
        let id = &stage.id;
        if filter.is_some_and(|f| !id.contains(f)) {
            continue;
        }
        // Only the overrides this module declares.
        let constants: naga::back::PipelineConstants = overrides
            .iter()
            .filter(|(k, _)| {
                stage
                    .module
                    .overrides
                    .iter()
                    .any(|(_, o)| o.name.as_deref() == Some(k))
            })
            .cloned()
            .collect();
        let (module, info) = naga::back::pipeline_constants::process_overrides(
            &stage.module,
            &stage.info,
            None,
            &constants,
        )
        .map_err(|e| format!("{id}: overrides: {e}"))?;
        let binds = bindings(&module);
        for ep in module
            .entry_points
            .iter()
            .filter(|e| e.stage == naga::ShaderStage::Compute)
        {
            let pipeline = naga::back::spv::PipelineOptions {
                shader_stage: naga::ShaderStage::Compute,
                entry_point: ep.name.clone(),
            };
            let spirv = naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
                .map_err(|e| format!("{id}::{}: SPIR-V: {e}", ep.name))?;
            match vulkan.compute_stats(&spirv, &ep.name, &binds) {
                Ok(executables) => {
                    for (exe, values) in executables {
                        let list: Vec<String> =
                            values.iter().map(|(k, v)| format!("{k} {v}")).collect();
                        println!("{id}::{} [{exe}]: {}", ep.name, list.join(", "));
                    }
                }
                Err(e) => println!("{id}::{}: {e}", ep.name),
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn overrides_parse_and_bad_ones_are_named() {
        let ok = parse_overrides(&["GAIN=true".into(), "BIAS=2".into(), "X=0.5".into()]).unwrap();
        assert_eq!(
            ok,
            vec![
                ("GAIN".to_string(), 1.0),
                ("BIAS".to_string(), 2.0),
                ("X".to_string(), 0.5)
            ]
        );
        let e = parse_overrides(&["BIAS".into()]).unwrap_err();
        assert!(e.contains("\"BIAS\""), "{e}");
        let e = parse_overrides(&["BIAS=two".into()]).unwrap_err();
        assert!(e.contains("\"two\""), "{e}");
    }

    /// The stages built into the binary are the checkout's (this test's binary is built from
    /// it): each file's stage is there with the same entry points, and every linked source
    /// parses and validates on its own. The binary has more: stages the build makes from
    /// templates (the cloud's density march), which no file holds.
    #[test]
    fn built_stages_are_the_checkouts() {
        let entries = |stages: Vec<Stage>| {
            let mut v: Vec<(String, Vec<String>)> = stages
                .into_iter()
                .map(|s| {
                    let mut e: Vec<String> = s
                        .module
                        .entry_points
                        .iter()
                        .map(|e| e.name.clone())
                        .collect();
                    e.sort();
                    (s.id, e)
                })
                .collect();
            v.sort();
            v
        };
        let built = entries(stages_of(Source::Built).expect("built stages validate"));
        let root = crate::crate_root();
        let checkout = entries(stages_of(Source::Checkout(&root)).expect("checkout validates"));
        for stage in &checkout {
            assert!(
                built.contains(stage),
                "{stage:?} is not built in as the checkout has it"
            );
        }
        assert!(
            built.iter().any(|(id, _)| id == "volume::cloud_march"),
            "the templated stage is missing"
        );
    }

    /// The layout built for the driver has every binding the shader declares, with the
    /// descriptor type its address space and type call for.
    #[test]
    fn bindings_follow_the_module() {
        let stages = crate::stages(&crate::crate_root()).expect("stages validate");
        let march = stages
            .iter()
            .find(|s| s.file.id() == "volume::volume_march")
            .expect("volume_march");
        let b = bindings(&march.module);
        let ty = |binding: u32| {
            b.iter()
                .find(|x| x.0 == 0 && x.1 == binding)
                .map(|x| x.2)
                .unwrap_or_else(|| panic!("binding {binding} missing from {b:?}"))
        };
        // params, density, linear_clamp, tf, ranges, light_in, scene_depth, colour_out, light_out
        assert_eq!(ty(0), vk::DescriptorType::UNIFORM_BUFFER);
        assert_eq!(ty(1), vk::DescriptorType::SAMPLED_IMAGE);
        assert_eq!(ty(2), vk::DescriptorType::SAMPLER);
        assert_eq!(ty(3), vk::DescriptorType::STORAGE_BUFFER);
        assert_eq!(ty(4), vk::DescriptorType::STORAGE_BUFFER);
        assert_eq!(ty(5), vk::DescriptorType::SAMPLED_IMAGE);
        assert_eq!(ty(6), vk::DescriptorType::SAMPLED_IMAGE);
        assert_eq!(ty(7), vk::DescriptorType::STORAGE_IMAGE);
        assert_eq!(ty(8), vk::DescriptorType::STORAGE_IMAGE);
        assert_eq!(b.len(), 9);
    }
}
