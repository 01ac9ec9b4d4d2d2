//! Each `#[repr(C)]` GPU struct matches its WGSL twin in `wgsl/shared/types.wgsl`: same member
//! names in the same order, same offsets, same size (as naga lays them out). No GPU needed.

use std::mem::{offset_of, size_of};

use lobelight::shaders::SHARED;
use lobelight::types::*;

struct RustLayout {
    name: &'static str,
    size: usize,
    members: Vec<(&'static str, usize)>,
}

macro_rules! layout {
    ($ty:ident { $($field:ident),* $(,)? }) => {
        RustLayout {
            name: stringify!($ty),
            size: size_of::<$ty>(),
            members: vec![$((stringify!($field), offset_of!($ty, $field))),*],
        }
    };
}

fn rust_layouts() -> Vec<RustLayout> {
    vec![
        layout!(Splat {
            center,
            radius,
            normal,
            material,
            diffuse,
            object
        }),
        layout!(SurfaceClip { x, y, z }),
        layout!(SplatLod {
            extent,
            top,
            parent_extent,
            parent_gap
        }),
        layout!(SplatChunk {
            center,
            centre_reach,
            first,
            ends,
            level_fit,
            parent_fit,
            parent_gap,
            _pad
        }),
        layout!(Material {
            specular,
            roughness
        }),
        layout!(Light {
            position,
            kind,
            direction,
            cos_outer,
            power,
            cos_inner,
            edge_u,
            area,
            edge_v,
            flags
        }),
        layout!(Photon {
            position,
            bounce,
            direction,
            splat,
            power,
            path
        }),
        layout!(Emitter {
            light,
            first,
            count,
            _pad0,
            _pad1,
            photon_power,
            falloff_norm
        }),
        layout!(TraceParams {
            seed,
            path_offset,
            path_count,
            emitter_count,
            max_depth,
            min_bounce,
            iteration_budget,
            _pad0
        }),
        layout!(PhotonViewParams {
            count,
            width,
            height,
            scale
        }),
        layout!(TraceCounters {
            stored,
            capacity,
            overflow,
            escaped,
            absorbed,
            depth_capped,
            aborted,
            _pad
        }),
        layout!(Ray {
            origin,
            t_max,
            direction,
            skip
        }),
        layout!(Hit {
            t,
            splat,
            aborted,
            _pad
        }),
        layout!(DistanceParams {
            axis,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(Lobe {
            axis,
            sharpness,
            irradiance,
            weight
        }),
        layout!(SplatLight {
            irradiance,
            photons,
            log_likelihood,
            weight,
            lobes,
            first_lobe
        }),
        layout!(BinnedPhoton {
            position,
            direction
        }),
        layout!(BinParams {
            origin,
            cell_size,
            dims,
            cell_count,
            inv_cell_size,
            photon_count,
            rank_chunk,
            sub
        }),
        layout!(EmParams {
            lobes,
            iterations,
            family,
            flags,
            radius,
            radius2,
            slab,
            inv_area,
            splat_count,
            active_count,
            iteration_begin,
            iteration_end,
            workgroup_size,
            prune,
            fit_candidates,
            gathered,
            list_first,
            smooth_radii,
            _pad1,
            _pad2
        }),
        layout!(DepositParams {
            power_scale,
            photon_count,
            splat_count,
            reach,
            first_splat,
            spread_max,
            _pad1,
            _pad2
        }),
        layout!(GatherParams {
            splat_count,
            samples,
            seed,
            shadow_bias,
            first,
            light_count,
            group_starts,
            group_members
        }),
        layout!(Camera {
            eye,
            near,
            forward,
            depth_tolerance,
            right,
            tan_x,
            up,
            tan_y,
            size,
            jitter,
            lod,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(ShadeParams {
            lobes_per_splat,
            family,
            light_count,
            area_samples,
            shadow_bias,
            seed,
            show,
            direct,
            area_first,
            area_count,
            sample,
            glossy_rays,
            background
        }),
        layout!(PresentParams {
            image_width,
            image_height,
            target_width,
            target_height,
            decode,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(TemporalParams {
            width,
            height,
            reset,
            max_frames,
            depth_tolerance,
            normal_cos,
            _pad0,
            _pad1
        }),
        layout!(TileParams {
            tiles_x,
            tiles_y,
            splat_count,
            entry_count
        }),
        layout!(PathParams {
            width,
            height,
            sample,
            seed,
            max_depth,
            light_count,
            show,
            shadow_bias,
            background
        }),
        layout!(DirectParams {
            splat_count,
            light_count,
            samples,
            seed,
            shadow_bias,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(GridParams {
            origin,
            cell_size,
            dims,
            cell_count,
            inv_cell_size,
            splat_count,
            entry_count,
            _pad0
        }),
        layout!(ScanParams {
            len,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(ToneParams {
            count,
            level,
            mode,
            _pad0,
            key,
            exposure,
            luminance_scale,
            epsilon
        }),
    ]
}

#[test]
fn rust_structs_match_wgsl_twins() {
    let text = SHARED.iter().find(|s| s.name == "types").unwrap().text;
    let module = naga::front::wgsl::parse_str(text).unwrap();
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let mut wgsl_structs = Vec::new();
    for (handle, ty) in module.types.iter() {
        let naga::TypeInner::Struct { members, span } = &ty.inner else {
            continue;
        };
        let name = ty.name.clone().unwrap();
        let rust = rust_layouts().into_iter().find(|r| r.name == name);
        let rust =
            rust.unwrap_or_else(|| panic!("WGSL struct {name} has no Rust twin in this test"));
        let wgsl_members: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap(), m.offset as usize))
            .collect();
        let rust_members: Vec<(String, usize)> = rust
            .members
            .iter()
            .map(|(n, o)| (n.to_string(), *o))
            .collect();
        assert_eq!(wgsl_members, rust_members, "member offsets of {name}");
        assert_eq!(*span as usize, rust.size, "size of {name}");
        assert_eq!(
            layouter[handle].size as usize, rust.size,
            "layouter size of {name}"
        );
        // Uniform and storage arrays of these need 16-byte multiples on every backend.
        assert_eq!(rust.size % 16, 0, "{name} should be a multiple of 16 bytes");
        wgsl_structs.push(name);
    }
    for r in rust_layouts() {
        assert!(
            wgsl_structs.iter().any(|n| n == r.name),
            "Rust struct {} has no WGSL twin",
            r.name
        );
    }
}
