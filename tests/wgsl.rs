//! Every WGSL module validates with naga, every kernel in every feature variant validates,
//! every struct shared with Rust has the same size and field offsets on both sides, and the
//! bindings and feature constants the WGSL declares are the Rust tables'.

use std::mem::{offset_of, size_of};

use chambre::gpu::kernels::{
    Access, BINDINGS, KERNELS, MODULES, RENDER, SCENE_BINDINGS, SCENE_GROUP, feature_constants,
    group_of, kernel_source,
};
use chambre::layout::*;
use naga::valid::{Capabilities, ValidationFlags, Validator};

fn validator() -> Validator {
    Validator::new(ValidationFlags::all(), Capabilities::empty())
}

fn parse_and_validate(source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    validator()
        .validate(&module)
        .unwrap_or_else(|e| panic!("{}", e.emit_to_string(source)));
    module
}

fn render_kernel_source() -> String {
    kernel_source(&RENDER)
}

/// Every kernel of the registry, specialised to each of the 64 feature sets, validates after
/// its override constants are substituted (what a driver compiles).
#[test]
fn every_kernel_validates_in_every_feature_variant() {
    for kernel in KERNELS {
        let source = kernel_source(kernel);
        let module = parse_and_validate(&source);
        let info = validator().validate(&module).unwrap();
        for features in 0..=FEATURES_ALL {
            let constants: naga::back::PipelineConstants = feature_constants(features)
                .into_iter()
                .map(|(name, value)| (name.to_string(), value))
                .collect();
            let (specialised, _) = naga::back::pipeline_constants::process_overrides(
                &module,
                &info,
                Some((naga::ShaderStage::Compute, kernel.entry_point)),
                &constants,
            )
            .unwrap_or_else(|e| panic!("{} with features {features:#x}: {e:?}", kernel.name));
            validator()
                .validate(&specialised)
                .unwrap_or_else(|e| panic!("{} with features {features:#x}: {e:?}", kernel.name));
        }
    }
}

/// How the shader accesses the binding `var`, in the registry's terms.
fn access_of(module: &naga::Module, var: &naga::GlobalVariable) -> Access {
    use naga::{ImageClass, ImageDimension, ScalarKind, TypeInner};
    match (var.space, &module.types[var.ty].inner) {
        (naga::AddressSpace::Uniform, _) => Access::Uniform,
        (naga::AddressSpace::Storage { access }, _)
            if access.contains(naga::StorageAccess::STORE) =>
        {
            Access::StorageReadWrite
        }
        (naga::AddressSpace::Storage { .. }, _) => Access::StorageRead,
        (naga::AddressSpace::Handle, TypeInner::Sampler { comparison: true }) => {
            Access::ComparisonSampler
        }
        (
            naga::AddressSpace::Handle,
            TypeInner::Image {
                dim,
                arrayed,
                class,
            },
        ) => match (dim, arrayed, class) {
            (
                ImageDimension::D2,
                false,
                ImageClass::Sampled {
                    kind: ScalarKind::Float,
                    multi: false,
                },
            ) => Access::FloatTexture,
            (
                ImageDimension::D2,
                false,
                ImageClass::Sampled {
                    kind: ScalarKind::Uint,
                    multi: false,
                },
            ) => Access::UintTexture,
            (ImageDimension::D2, true, ImageClass::Depth { multi: false }) => {
                Access::DepthTextureArray
            }
            other => panic!(
                "{:?}: a texture the registry has no name for: {other:?}",
                var.name
            ),
        },
        (space, ty) => panic!("{:?}: unexpected binding {space:?} {ty:?}", var.name),
    }
}

/// The bindings wgsl/bindings.wgsl declares are exactly `BINDINGS`: numbers, names, access
/// and groups (the scene's group holds exactly `SCENE_BINDINGS`); and each kernel's binding
/// list is a subset of them.
#[test]
fn declared_bindings_are_the_rust_table() {
    let module = parse_and_validate(&render_kernel_source());
    let mut declared: Vec<(u32, String, Access)> = module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let binding = var.binding.as_ref()?;
            let table = BINDINGS.iter().find(|b| b.binding == binding.binding);
            let group = table.map(group_of);
            assert_eq!(Some(binding.group), group, "{:?}", var.name);
            Some((
                binding.binding,
                var.name.clone().unwrap(),
                access_of(&module, var),
            ))
        })
        .collect();
    let scene_group = BINDINGS.iter().filter(|b| group_of(b) == SCENE_GROUP);
    assert_eq!(scene_group.count(), SCENE_BINDINGS.len());
    assert!(SCENE_BINDINGS.iter().all(|b| b.dynamic_size == 0));
    declared.sort_by_key(|d| d.0);
    for kernel in KERNELS {
        assert!(
            kernel.bindings.iter().all(|b| BINDINGS.contains(b)),
            "{}",
            kernel.name
        );
    }
    let table: Vec<(u32, String, Access)> = BINDINGS
        .iter()
        .map(|b| (b.binding, b.name.to_string(), b.access))
        .collect();
    assert_eq!(declared, table);
}

/// The override constants of the kernel are exactly `layout::FEATURES`, each a bool that is
/// true by default (the general kernel).
#[test]
fn feature_constants_are_the_rust_table() {
    let module = parse_and_validate(&render_kernel_source());
    let mut declared: Vec<String> = module
        .overrides
        .iter()
        .map(|(_, o)| {
            assert_eq!(
                module.types[o.ty].inner,
                naga::TypeInner::Scalar(naga::Scalar::BOOL),
                "{:?}",
                o.name
            );
            o.name.clone().unwrap()
        })
        .collect();
    declared.sort();
    let mut table: Vec<String> = FEATURES.iter().map(|(n, _)| n.to_string()).collect();
    table.sort();
    assert_eq!(declared, table);
}

#[test]
fn every_library_module_parses_with_its_dependencies() {
    // Each prefix of the composition order is a valid module on its own (libraries only
    // depend on what comes before them), except the last two, which read the kernel bindings.
    let mut source = wgsl_prelude();
    for (name, text) in &MODULES[..5] {
        source += text;
        naga::front::wgsl::parse_str(&source)
            .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(&source)));
    }
}

#[test]
fn every_wgsl_module_names_an_existing_rust_twin() {
    let root = env!("CARGO_MANIFEST_DIR");
    for (name, text) in MODULES {
        if name == "types.wgsl" {
            assert!(text.contains("src/layout.rs"));
            continue;
        }
        let line = text
            .lines()
            .find(|l| l.starts_with("// Mirrors: "))
            .unwrap_or_else(|| panic!("{name} names no twin"));
        let twin = line
            .trim_start_matches("// Mirrors: ")
            .split_whitespace()
            .next()
            .unwrap()
            .trim_end_matches([',', '.']);
        assert!(
            std::path::Path::new(root).join(twin).exists(),
            "{name}: twin {twin} does not exist"
        );
    }
}

fn check_struct(module: &naga::Module, name: &str, size: usize, fields: &[(&str, usize)]) {
    let (_, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{name} missing in WGSL"));
    let naga::TypeInner::Struct { members, span } = &ty.inner else {
        panic!("{name} is not a struct")
    };
    assert_eq!(
        *span as usize, size,
        "{name}: WGSL size {span} != Rust size {size}"
    );
    assert_eq!(members.len(), fields.len(), "{name}: field count differs");
    for (member, (field, offset)) in members.iter().zip(fields) {
        assert_eq!(
            member.name.as_deref(),
            Some(*field),
            "{name}: field order/name differs"
        );
        assert_eq!(
            member.offset as usize, *offset,
            "{name}.{field}: WGSL offset {} != Rust {offset}",
            member.offset
        );
    }
}

macro_rules! layout {
    ($module:expr, $ty:ident { $($field:ident),* }) => {
        check_struct(&$module, stringify!($ty), size_of::<$ty>(), &[$((stringify!($field), offset_of!($ty, $field))),*]);
    };
}

#[test]
fn shared_structs_have_identical_layouts() {
    let module = parse_and_validate(&render_kernel_source());
    layout!(
        module,
        GpuBvhNode {
            min,
            prim_count,
            max,
            first_index
        }
    );
    layout!(
        module,
        GpuCwNode {
            p,
            e_imask,
            child_base,
            prim_base,
            child_meta,
            q_lo_x,
            q_hi_x,
            q_lo_y,
            q_hi_y,
            q_lo_z,
            q_hi_z
        }
    );
    layout!(
        module,
        GpuPrimitive {
            p0,
            kind,
            p1,
            material,
            p2,
            normals
        }
    );
    layout!(module, GpuNormals { n });
    layout!(
        module,
        GpuRay {
            origin,
            t_max,
            direction,
            _pad0
        }
    );
    layout!(module, GpuHit { prim, t, b1, b2 });
    layout!(
        module,
        GpuPathRay {
            origin,
            time,
            direction,
            skip
        }
    );
    layout!(
        module,
        GpuPath {
            throughput,
            pixel,
            radiance,
            sample,
            bounce_weight,
            rays,
            shadow_count,
            truncated,
            bsdf_pdf,
            camera_weight
        }
    );
    layout!(
        module,
        GpuShadowRay {
            origin,
            t_max,
            direction,
            time,
            skip_a,
            skip_b,
            _pad0,
            _pad1
        }
    );
    layout!(module, GpuShadowTerm { f, light });
    layout!(
        module,
        GpuWave {
            depth,
            shadow_stride,
            path_capacity,
            _pad0
        }
    );
    layout!(module, GpuWaveArgs { paths, shadows });
    layout!(
        module,
        GpuReflector {
            center,
            radius,
            eye,
            count,
            kind,
            minor,
            height,
            mirror,
            radii,
            orientation,
            control,
            sees_itself,
            torus_half,
            eye_uv
        }
    );
    layout!(
        module,
        GpuReflection {
            point,
            steps,
            normal,
            shown,
            uv,
            depth,
            degenerate
        }
    );
    layout!(
        module,
        GpuDrawArgs {
            index_count,
            instance_count,
            first_index,
            base_vertex,
            first_instance
        }
    );
    layout!(
        module,
        GpuMaterial {
            diffuse,
            model,
            specular,
            shininess,
            mirror,
            light_samples,
            emission,
            ior,
            texture,
            _pad0,
            _pad1,
            _pad2
        }
    );
    layout!(
        module,
        GpuTexture {
            offset,
            width,
            height,
            wrap
        }
    );
    layout!(module, GpuTexCoords { uv });
    layout!(
        module,
        GpuLight {
            p0,
            kind,
            p1,
            samples,
            p2,
            prim,
            color,
            strata_columns
        }
    );
    layout!(
        module,
        GpuCamera {
            lens_to_world_x,
            focal_length_mm,
            lens_to_world_y,
            lens_radius_mm,
            lens_to_world_z,
            units_per_mm,
            lens_center,
            inv_focal_length_mm,
            film_center,
            film_width_mm,
            film_u,
            film_height_mm,
            film_v,
            aperture_blades,
            aperture_table_offset,
            shutter_open,
            shutter_span,
            focus_surface,
            focus_radius_mm,
            projection,
            lens_surface_count,
            lens_table_offset,
            spectral,
            _pad0,
            _pad1,
            _pad2
        }
    );
    layout!(
        module,
        GpuFrame {
            width,
            height,
            spp,
            max_depth,
            seed,
            pixel_sampler,
            light_count,
            node_count,
            plane_start,
            plane_count,
            traversal_cap,
            pixel_strata_columns,
            lens_sampler,
            lens_strata_columns,
            pixel_table_offset,
            lens_table_offset,
            background,
            light_samples_per_vertex,
            ambient,
            motion_base,
            progressive,
            integrator,
            rr_depth,
            vertex_dimension_pairs,
            light_choice_start,
            light_choice_pairs,
            light_choice_offset,
            light_power_total
        }
    );
    layout!(
        module,
        GpuPass {
            tile_x,
            tile_y,
            tile_width,
            tile_height,
            sample_start,
            sample_count,
            light_sample_start,
            light_sample_count,
            commit,
            loop_check,
            listed_pixels,
            scratch_offset,
            aov_offset,
            _pad1,
            _pad2,
            _pad3
        }
    );
}

#[test]
fn generated_constants_match_rust() {
    let module = parse_and_validate(&render_kernel_source());
    let constant = |name: &str| -> u32 {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap();
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref e => panic!("{name}: {e:?}"),
        }
    };
    assert_eq!(constant("BVH_STACK_SIZE"), BVH_STACK_SIZE);
    assert_eq!(constant("MODEL_EMITTER"), MODEL_EMITTER);
    assert_eq!(constant("LIGHT_AREA"), LIGHT_AREA);
    assert_eq!(constant("NONE"), NONE);
    assert_eq!(constant("SAMPLER_SOBOL"), SAMPLER_SOBOL);
    assert_eq!(constant("POISSON_SETS"), POISSON_SETS);
}

/// Each kernel's binding list in the registry is exactly what its entry point reads or writes,
/// so the pipeline builder's layout and the kernel cannot drift apart.
#[test]
fn each_kernel_lists_exactly_the_bindings_it_uses() {
    for kernel in KERNELS {
        let module = parse_and_validate(&kernel_source(kernel));
        let info = validator().validate(&module).unwrap();
        let index = module
            .entry_points
            .iter()
            .position(|e| e.name == kernel.entry_point)
            .unwrap_or_else(|| panic!("{}: no entry point", kernel.name));
        let uses = info.get_entry_point(index);
        let mut used: Vec<u32> = module
            .global_variables
            .iter()
            .filter(|(handle, var)| var.binding.is_some() && !uses[*handle].is_empty())
            .map(|(_, var)| var.binding.as_ref().unwrap().binding)
            .collect();
        used.sort();
        let listed: Vec<u32> = kernel.bindings.iter().map(|b| b.binding).collect();
        assert_eq!(used, listed, "{}", kernel.name);
    }
}

/// Each of the preview's render pipelines lists, group by group, exactly the bindings its
/// entry points read, with the shader's numbers, names and access; and each binding is visible
/// to exactly the stages that read it, over every pipeline that binds it (the shading group is
/// the main pass's and the reflection pass's).
#[test]
fn each_preview_pipeline_lists_exactly_the_bindings_it_uses() {
    use chambre::gpu::kernels::Binding;
    use std::collections::BTreeMap;
    type Key = (u32, u32, String);
    let mut described_stages: BTreeMap<Key, (Binding, wgpu::ShaderStages)> = BTreeMap::new();
    for pipeline in chambre::preview::PIPELINES {
        let module = parse_and_validate(&(pipeline.source)());
        let info = validator().validate(&module).unwrap();
        let mut used: BTreeMap<Key, (Access, wgpu::ShaderStages)> = BTreeMap::new();
        let stages = [
            (Some(pipeline.vertex), wgpu::ShaderStages::VERTEX),
            (pipeline.fragment, wgpu::ShaderStages::FRAGMENT),
        ];
        for (entry, stage) in stages {
            let Some(entry) = entry else { continue };
            let index = module
                .entry_points
                .iter()
                .position(|e| e.name == entry)
                .unwrap_or_else(|| panic!("{}: no entry point {entry}", pipeline.name));
            let uses = info.get_entry_point(index);
            for (handle, var) in module.global_variables.iter() {
                let Some(binding) = &var.binding else {
                    continue;
                };
                if uses[handle].is_empty() {
                    continue;
                }
                let key = (binding.group, binding.binding, var.name.clone().unwrap());
                let access = access_of(&module, var);
                used.entry(key).or_insert((access, stage)).1 |= stage;
            }
        }
        let mut listed: BTreeMap<Key, Access> = BTreeMap::new();
        for (group, bindings) in pipeline.groups.iter().enumerate() {
            for b in *bindings {
                let key = (group as u32, b.binding, b.name.to_string());
                listed.insert(key.clone(), b.access);
                let stages = used.get(&key).map_or(wgpu::ShaderStages::NONE, |u| u.1);
                described_stages
                    .entry(key)
                    .or_insert((*b, wgpu::ShaderStages::NONE))
                    .1 |= stages;
            }
        }
        let used_access: BTreeMap<Key, Access> = used
            .iter()
            .map(|(k, (access, _))| (k.clone(), *access))
            .collect();
        assert_eq!(
            listed, used_access,
            "{}: listed against used",
            pipeline.name
        );
    }
    for ((group, number, name), (binding, stages)) in described_stages {
        assert_eq!(
            binding.visibility, stages,
            "group {group} binding {number} `{name}`: visible to the stages that read it"
        );
    }
}

/// The raster preview's structs (its vertex, uniforms, reflection pass and shadow maps' lights)
/// have the Rust layouts, and its shaders validate.
#[test]
fn preview_structs_have_identical_layouts() {
    use chambre::preview::{PreviewUniforms, PreviewVertex, ReflectorPass, ShadowLight};
    let module = parse_and_validate(&chambre::preview::shader_source());
    layout!(
        module,
        PreviewVertex {
            position,
            material,
            normal,
            reflector
        }
    );
    let uniforms = [
        ("clip", offset_of!(PreviewUniforms, clip)),
        ("light_count", offset_of!(PreviewUniforms, light_count)),
        ("max_depth", offset_of!(PreviewUniforms, max_depth)),
        ("_pad1", offset_of!(PreviewUniforms, _pad)),
        ("_pad2", offset_of!(PreviewUniforms, _pad) + 4),
        ("ambient", offset_of!(PreviewUniforms, ambient)),
        ("eye", offset_of!(PreviewUniforms, eye)),
        ("background", offset_of!(PreviewUniforms, background)),
    ];
    check_struct(
        &module,
        "PreviewUniforms",
        size_of::<PreviewUniforms>(),
        &uniforms,
    );
    let pass = [
        ("far", offset_of!(ReflectorPass, far)),
        ("id", offset_of!(ReflectorPass, id)),
        ("material", offset_of!(ReflectorPass, material)),
        ("solves", offset_of!(ReflectorPass, solves)),
    ];
    check_struct(&module, "ReflectorPass", size_of::<ReflectorPass>(), &pass);
    let shadow = [
        ("first", offset_of!(ShadowLight, first)),
        ("layers", offset_of!(ShadowLight, layers)),
        ("texel", offset_of!(ShadowLight, texel)),
        ("origins", offset_of!(ShadowLight, origins)),
    ];
    check_struct(&module, "ShadowLight", size_of::<ShadowLight>(), &shadow);
    parse_and_validate(chambre::preview::SHADOW_SHADER);
}
