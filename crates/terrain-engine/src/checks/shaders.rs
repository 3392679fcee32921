//! Every WGSL pass, as combined by the import step in every variant, parses and validates with
//! naga (no GPU needed), and the uniform block's Rust twin has the WGSL struct's size.

use terrain_engine::gpu::pipeline::Shader;
use terrain_engine::gpu::shaders::FLAGS;

/// The shader of pass `name`, among every pass's (`lod::shaders`).
pub(super) fn shader(name: &str) -> &'static Shader {
    terrain_engine::lod::shaders()
        .find(|s| s.name == name)
        .unwrap_or_else(|| panic!("no pass {name}"))
}

fn validate(name: &str, flags: &[&str]) -> naga::Module {
    let source = shader(name)
        .compose(flags)
        .unwrap_or_else(|e| panic!("{name} {flags:?}: {e}"));
    validate_source(name, flags, &source)
}

/// Every WGSL file of a pass in `shaders/` (the imported ones are in `shaders/shared/`) is the
/// shader of one pass, and each pass's name is its own: none is left out of the checks.
#[test]
fn every_wgsl_file_is_one_pass_shader() {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/shaders");
    let mut files: Vec<String> = std::fs::read_dir(dir)
        .expect("shaders/")
        .filter_map(|e| {
            let name = e.ok()?.file_name().into_string().ok()?;
            Some(name.strip_suffix(".wgsl")?.to_string())
        })
        .collect();
    let mut passes: Vec<String> = terrain_engine::lod::shaders()
        .map(|s| s.name.into())
        .collect();
    files.sort();
    passes.sort();
    assert_eq!(passes, files);
}

fn validate_source(name: &str, flags: &[&str], source: &str) -> naga::Module {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name} {flags:?}: {}", e.emit_to_string(source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name} {flags:?}: {}", e.emit_to_string(source)));
    module
}

/// Variants differing only in flags their pass never tests compose to the same source (checked
/// once per pass, all flags against its own). A pass testing up to [`EXHAUSTIVE`] flags is
/// validated in every variant; one testing more (the terrain pass tests 16: 65,536 variants,
/// 265 s of naga) in every single flag on and off and in a set of variants that holds every
/// combination of values of every three of its flags (a covering array of strength 3): a flag
/// that breaks the WGSL alone, or only beside one or two others, is caught.
#[test]
fn every_pass_validates_in_every_variant() {
    let mut count = 0;
    for shader in terrain_engine::lod::shaders() {
        let name = shader.name;
        let tested = shader.tested_flags();
        let own = tested.defs();
        assert_eq!(
            shader.compose(&FLAGS).unwrap(),
            shader.compose(&own).unwrap(),
            "{name}: a flag outside {own:?} changes its source"
        );
        for mask in variants(own.len()) {
            let flags: Vec<&str> = own
                .iter()
                .enumerate()
                .filter(|(k, _)| mask & (1 << k) != 0)
                .map(|(_, f)| *f)
                .collect();
            validate(name, &flags);
            count += 1;
        }
    }
    assert!(count >= terrain_engine::lod::shaders().count());
}

/// Passes testing this many flags or fewer are validated in all their variants.
const EXHAUSTIVE: usize = 9;

/// The variants of a pass testing `n` flags that the checks compose, as masks of those flags:
/// all of them up to [`EXHAUSTIVE`] flags, covering triples beyond.
pub(super) fn variants(n: usize) -> Vec<u32> {
    match n <= EXHAUSTIVE {
        true => (0..(1u32 << n)).collect(),
        false => covering_triples(n),
    }
}

/// Masks of `n` flags in which every three flags take each of their eight combinations of values
/// at least once, and every flag is set alone and unset alone: greedy, each mask the one of 64
/// candidates (a fixed pseudo-random sequence) that covers the most combinations still missing.
fn covering_triples(n: usize) -> Vec<u32> {
    let all = (1u32 << n) - 1;
    let mut masks: Vec<u32> = (0..n).flat_map(|k| [1 << k, all ^ (1 << k)]).collect();
    masks.extend([0, all]);
    let triples: Vec<[usize; 3]> = (0..n)
        .flat_map(|i| (i + 1..n).flat_map(move |j| (j + 1..n).map(move |k| [i, j, k])))
        .collect();
    let value = |m: u32, [i, j, k]: [usize; 3]| {
        (m >> i & 1 | (m >> j & 1) << 1 | (m >> k & 1) << 2) as usize
    };
    let mut missing: Vec<[bool; 8]> = vec![[true; 8]; triples.len()];
    let cover = |m: u32, missing: &mut Vec<[bool; 8]>| {
        for (t, seen) in triples.iter().zip(missing.iter_mut()) {
            seen[value(m, *t)] = false;
        }
    };
    for &m in &masks {
        cover(m, &mut missing);
    }
    let mut state = 0x2545_f491_4f6c_dd1d_u64;
    while missing.iter().any(|s| s.iter().any(|&b| b)) {
        let gain = |m: u32| {
            triples
                .iter()
                .zip(&missing)
                .filter(|(t, seen)| seen[value(m, **t)])
                .count()
        };
        let best = (0..64)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state as u32 & all
            })
            .max_by_key(|&m| gain(m))
            .expect("candidates");
        cover(best, &mut missing);
        masks.push(best);
    }
    masks
}

/// The covering masks hold every value of every three flags, in far fewer variants than all.
#[test]
fn the_covering_masks_cover_every_triple() {
    let masks = covering_triples(16);
    for i in 0..16 {
        for j in i + 1..16 {
            for k in j + 1..16 {
                for v in 0..8u32 {
                    assert!(
                        masks.iter().any(|m| (m >> i & 1) == (v & 1)
                            && (m >> j & 1) == (v >> 1 & 1)
                            && (m >> k & 1) == (v >> 2 & 1)),
                        "flags {i}, {j}, {k} never {v:03b}"
                    );
                }
            }
        }
    }
    assert!(masks.len() < 100, "{} masks", masks.len());
}

/// (name, offset, size) of each field of a Rust struct shared with WGSL, in declaration order.
macro_rules! rust_layout {
    ($t:ty { $($f:ident),* $(,)? }) => {{
        let z: $t = bytemuck::Zeroable::zeroed();
        vec![$((
            stringify!($f).to_string(),
            std::mem::offset_of!($t, $f) as u32,
            std::mem::size_of_val(&z.$f) as u32,
        )),*]
    }};
}

/// (name, offset, size) of each member of the WGSL struct `name`, and the struct's size.
fn wgsl_layout(module: &naga::Module, name: &str) -> (Vec<(String, u32, u32)>, u32) {
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, ty) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some(name))
        .unwrap_or_else(|| panic!("{name} in the WGSL"));
    let naga::TypeInner::Struct { members, .. } = &ty.inner else {
        panic!("{name} is not a struct");
    };
    let fields = members
        .iter()
        .map(|m| {
            (
                m.name.clone().unwrap_or_default(),
                m.offset,
                layouter[m.ty].size,
            )
        })
        .collect();
    (fields, layouter[handle].size)
}

#[test]
fn uniform_structs_match_the_wgsl_field_by_field() {
    use std::mem::size_of;
    use terrain_engine::gpu::uniforms::*;
    let module = validate("warp_zoom", &[]);
    let structs = [
        (
            "Frame",
            rust_layout!(FrameUniforms {
                camera,
                shading,
                atlas,
                detail,
                mesh,
                blocks,
                march
            }),
            size_of::<FrameUniforms>(),
        ),
        (
            "CameraUniforms",
            rust_layout!(CameraUniforms {
                view_proj,
                inv_view_proj,
                eye,
                pixel_scale,
                image,
                view,
                pad
            }),
            size_of::<CameraUniforms>(),
        ),
        (
            "ShadingUniforms",
            rust_layout!(ShadingUniforms {
                sun,
                daylight,
                sun_top,
                air_mass,
                sky_light,
                exposure,
                haze_per_m,
                haze_height_m,
                outside,
                plain_m,
                margin_m,
                margin_lo_m,
                margin_hi_m,
                pad
            }),
            size_of::<ShadingUniforms>(),
        ),
        (
            "AtlasUniforms",
            rust_layout!(AtlasUniforms {
                level,
                offset,
                inv_spacing,
                d_atlas,
                levels,
                max_m,
                water_m,
                tile,
                border,
                pad
            }),
            size_of::<AtlasUniforms>(),
        ),
        (
            "DetailUniforms",
            rust_layout!(DetailUniforms {
                octave,
                octaves,
                bias,
                shore_m,
                pad
            }),
            size_of::<DetailUniforms>(),
        ),
        (
            "MeshUniforms",
            rust_layout!(MeshUniforms {
                phi_offset,
                mesh_offset,
                n,
                mesh,
                d0,
                importance_max,
                phi_s,
                phi_t
            }),
            size_of::<MeshUniforms>(),
        ),
        (
            "BlockUniforms",
            rust_layout!(BlockUniforms {
                cells,
                index_bits,
                levels,
                pad
            }),
            size_of::<BlockUniforms>(),
        ),
        (
            "MarchUniforms",
            rust_layout!(MarchUniforms { lo, hi, step, pad }),
            size_of::<MarchUniforms>(),
        ),
        (
            "Octave",
            rust_layout!(OctaveGpu {
                lattice,
                phase,
                scale,
                weight,
                seed,
                pad
            }),
            size_of::<OctaveGpu>(),
        ),
    ];
    for (name, rust, size) in structs {
        let (wgsl, wgsl_size) = wgsl_layout(&module, name);
        assert_eq!(rust, wgsl, "{name}: (field, offset, size) in Rust and WGSL");
        assert_eq!(size as u32, wgsl_size, "{name}: size");
    }
}

#[test]
fn the_planet_block_matches_the_wgsl_field_by_field() {
    use std::mem::size_of;
    use terrain_engine::lod::clipmaps::pass::*;
    let module = validate("clipmaps", &["NOISE"]);
    let structs = [
        (
            "Planet",
            rust_layout!(PlanetUniforms {
                east,
                radius,
                north,
                eye_m,
                up,
                sin_lat,
                sun,
                cos_lat,
                texel_origin,
                texel_frac,
                texels_per_rad,
                phi_steps,
                rings_per_level,
                first_vertex,
                vertex_count,
                nadir,
                inner_ring,
                levels,
                octaves,
                min_spacing,
                bias,
                water_m,
                pad0,
                pad1,
                pad2,
                octave
            }),
            size_of::<PlanetUniforms>(),
        ),
        (
            "SphereOctave",
            rust_layout!(SphereOctaveUniforms {
                lattice,
                seed,
                phase,
                scale,
                weight,
                pad0,
                pad1,
                pad2
            }),
            size_of::<SphereOctaveUniforms>(),
        ),
    ];
    for (name, rust, size) in structs {
        let (wgsl, wgsl_size) = wgsl_layout(&module, name);
        assert_eq!(rust, wgsl, "{name}: (field, offset, size) in Rust and WGSL");
        assert_eq!(size as u32, wgsl_size, "{name}: size");
    }
}

#[test]
fn view_constants_in_wgsl_are_the_rust_enum() {
    use terrain_engine::View;
    let module = validate("terrain", &[]);
    let mut found = 0;
    for (_, c) in module.constants.iter() {
        let Some(name) = c.name.as_deref().and_then(|n| n.strip_prefix("VIEW_")) else {
            continue;
        };
        let view = View::parse(&name.to_lowercase().replace('_', "-"))
            .unwrap_or_else(|| panic!("VIEW_{name} names no View"));
        let value = match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::U32(v)) => v,
            ref e => panic!("VIEW_{name} is {e:?}"),
        };
        assert_eq!(value, view as u32, "VIEW_{name}");
        found += 1;
    }
    assert_eq!(found, View::ALL.len(), "a VIEW_ constant per View");
}

/// The bump fade's noise RMS and model factor (shaders/shared/fade.wgsl) are the planar noise's,
/// src/detail.rs's.
#[test]
fn the_fades_constants_are_the_noises() {
    let module = validate("terrain", &["NOISE", "BUMP", "BUMP_FADE"]);
    let constant = |name: &str| {
        let (_, c) = module
            .constants
            .iter()
            .find(|(_, c)| c.name.as_deref() == Some(name))
            .unwrap_or_else(|| panic!("{name} in the terrain pass with BUMP_FADE"));
        match module.global_expressions[c.init] {
            naga::Expression::Literal(naga::Literal::F32(v)) => v,
            ref e => panic!("{name} is {e:?}"),
        }
    };
    assert_eq!(
        constant("FADE_NOISE_RMS"),
        terrain_engine::detail::NOISE_RMS as f32
    );
    // The model's factor: the octave's noise frequency is its lattice frequency over
    // LATTICE_PER_CYCLE.
    let model = 1.0
        / (terrain_engine::detail::LATTICE_PER_CYCLE * terrain_engine::detail::LATTICE_PER_CYCLE);
    assert_eq!(constant("FADE_MODEL"), model as f32);
}

#[test]
fn flags_drop_the_noise_code() {
    let with = shader("warp_zoom").compose(&["DETAIL"]).unwrap();
    let without = shader("warp_zoom").compose(&[]).unwrap();
    assert!(with.contains("fn gradient_noise") && with.contains("octave_local("));
    assert!(!without.contains("fn gradient_noise") && !without.contains("octave_local("));
    assert_eq!(with.matches("struct Frame").count(), 1);
}

#[test]
fn only_the_counting_variant_tallies() {
    for shader in terrain_engine::lod::shaders() {
        let plain = shader.compose(&["NOISE", "DETAIL", "SHADOWS"]).unwrap();
        assert!(
            !plain.contains("tally.") && !plain.contains("atomicAdd"),
            "{}",
            shader.name
        );
    }
    let counting = shader("terrain")
        .compose(&["COUNT_WORK", "SHADOWS"])
        .unwrap();
    assert!(counting.contains("tally.y += 1u") && counting.contains("atomicAdd(&work"));
}
