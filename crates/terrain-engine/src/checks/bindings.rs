//! Every pass's bindings, declared once in Rust (`terrain_engine::gpu::bindings`), are the ones its WGSL
//! declares in every variant: the same group, index, name and kind, as naga reflects them from the
//! composed source (no GPU needed).

use terrain_engine::gpu::bindings::Kind;
use terrain_engine::gpu::shaders::{FLAGS, Key};

type Declared = Vec<(u32, u32, String, Kind)>;

/// The `@group @binding` variables of a composed source.
fn reflect(name: &str, source: &str) -> Declared {
    let module = naga::front::wgsl::parse_str(source)
        .unwrap_or_else(|e| panic!("{name}: {}", e.emit_to_string(source)));
    let mut declared: Declared = module
        .global_variables
        .iter()
        .filter_map(|(_, var)| {
            let binding = var.binding.as_ref()?;
            let var_name = var.name.clone().unwrap_or_default();
            let kind = match var.space {
                naga::AddressSpace::Uniform => Kind::Uniform,
                naga::AddressSpace::Storage { access } => {
                    if access.contains(naga::StorageAccess::STORE) {
                        Kind::StorageRw
                    } else {
                        Kind::Storage
                    }
                }
                naga::AddressSpace::Handle => match module.types[var.ty].inner {
                    naga::TypeInner::Image {
                        dim: naga::ImageDimension::D2,
                        arrayed: false,
                        class:
                            naga::ImageClass::Sampled {
                                kind: naga::ScalarKind::Uint,
                                multi: false,
                            },
                    } => Kind::UintTexture,
                    naga::TypeInner::Image {
                        dim: naga::ImageDimension::D2,
                        arrayed: false,
                        class:
                            naga::ImageClass::Sampled {
                                kind: naga::ScalarKind::Float,
                                multi: false,
                            },
                    } => Kind::FloatTexture,
                    ref other => panic!("{name}: {var_name} is a {other:?}, no Kind of the passes"),
                },
                other => panic!("{name}: {var_name} in {other:?}"),
            };
            Some((binding.group, binding.binding, var_name, kind))
        })
        .collect();
    declared.sort_by_key(|d| (d.0, d.1));
    declared
}

/// Each pass's variants as [`super::shaders`] validates them (every variant of the flags its WGSL
/// tests, or covering triples beyond nine), each with the flags it does not test all off and all
/// on: a binding listed under a flag its WGSL never tests is caught by the second.
#[test]
fn every_pass_declares_its_listed_bindings_in_every_variant() {
    let mut checked = 0;
    for shader in terrain_engine::lod::shaders() {
        let (name, bindings) = (shader.name, shader.bindings);
        let own = shader.tested_flags().defs();
        let untested: Vec<&str> = FLAGS.iter().copied().filter(|f| !own.contains(f)).collect();
        for mask in super::shaders::variants(own.len()) {
            let flags: Vec<&str> = own
                .iter()
                .enumerate()
                .filter(|(k, _)| mask & (1 << k) != 0)
                .map(|(_, f)| *f)
                .collect();
            let source = shader
                .compose(&flags)
                .unwrap_or_else(|e| panic!("{name} {flags:?}: {e}"));
            let wgsl = reflect(name, &source);
            for extra in [&[][..], &untested[..]] {
                let all: Vec<&str> = flags.iter().chain(extra).copied().collect();
                let key = Key::of(&all);
                let mut listed: Declared = bindings
                    .iter()
                    .filter(|b| b.declared(key))
                    .map(|b| (b.group, b.index, b.name.to_string(), b.kind))
                    .collect();
                listed.sort_by_key(|d| (d.0, d.1));
                assert_eq!(
                    listed, wgsl,
                    "{name} {all:?}: (group, binding, name, kind) listed in Rust and declared in WGSL"
                );
                checked += 1;
            }
        }
    }
    assert!(checked >= 2 * terrain_engine::lod::shaders().count());
}
