//! A pipeline layout of every binding a stage's WGSL declares, read with naga: for stages of
//! several entry points, whose passes bind the same buffers though each reads only some (a
//! layout derived from one entry point would hold only the bindings it reads).

use crate::error::{Error, Result};
use crate::shaders::Stage;

/// The layout of every buffer binding `source` (the stage's resolved WGSL) declares, one bind
/// group a group index up to its highest.
pub fn declared(device: &wgpu::Device, stage: Stage, source: &str) -> Result<wgpu::PipelineLayout> {
    let module = naga::front::wgsl::parse_str(source)
        .map_err(|e| Error::Internal(format!("{stage}: {}", e.emit_to_string(source))))?;
    let mut groups: Vec<Vec<wgpu::BindGroupLayoutEntry>> = Vec::new();
    for (_, var) in module.global_variables.iter() {
        let Some(binding) = &var.binding else {
            continue;
        };
        let ty = match var.space {
            naga::AddressSpace::Uniform => wgpu::BufferBindingType::Uniform,
            naga::AddressSpace::Storage { access } => wgpu::BufferBindingType::Storage {
                read_only: !access.contains(naga::StorageAccess::STORE),
            },
            other => {
                return Err(Error::Internal(format!(
                    "{stage}: binding {} of group {} is in {other:?}, which a stage of several \
                     entry points cannot bind",
                    binding.binding, binding.group
                )));
            }
        };
        let group = binding.group as usize;
        if groups.len() <= group {
            groups.resize_with(group + 1, Vec::new);
        }
        groups[group].push(wgpu::BindGroupLayoutEntry {
            binding: binding.binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        });
    }
    let layouts: Vec<wgpu::BindGroupLayout> = groups
        .iter()
        .map(|entries| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(stage.name()),
                entries,
            })
        })
        .collect();
    let refs: Vec<Option<&wgpu::BindGroupLayout>> = layouts.iter().map(Some).collect();
    Ok(
        device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(stage.name()),
            bind_group_layouts: &refs,
            immediate_size: 0,
        }),
    )
}
