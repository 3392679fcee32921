//! Every WGSL pass, as combined by the import step in every variant, parses and validates with
//! naga (no GPU needed), and the uniform block's Rust twin has the WGSL struct's size.

use terrain::gpu::shaders::{FLAGS, PASSES, compose};
use terrain::gpu::uniforms::FrameUniforms;

fn validate(name: &str, flags: &[&str]) -> naga::Module {
    let source = compose(name, flags).unwrap_or_else(|e| panic!("{name} {flags:?}: {e}"));
    let module = naga::front::wgsl::parse_str(&source)
        .unwrap_or_else(|e| panic!("{name} {flags:?}: {}", e.emit_to_string(&source)));
    naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::default(),
    )
    .validate(&module)
    .unwrap_or_else(|e| panic!("{name} {flags:?}: {}", e.emit_to_string(&source)));
    module
}

#[test]
fn every_pass_validates_in_every_variant() {
    let mut count = 0;
    for (name, _) in PASSES {
        for mask in 0..(1u32 << FLAGS.len()) {
            let flags: Vec<&str> = FLAGS
                .iter()
                .enumerate()
                .filter(|(k, _)| mask & (1 << k) != 0)
                .map(|(_, f)| *f)
                .collect();
            validate(name, &flags);
            count += 1;
        }
    }
    assert_eq!(count, PASSES.len() << FLAGS.len());
}

#[test]
fn frame_uniforms_match_the_wgsl_layout() {
    let module = validate("warp_zoom", &[]);
    let mut layouter = naga::proc::Layouter::default();
    layouter.update(module.to_ctx()).unwrap();
    let (handle, _) = module
        .types
        .iter()
        .find(|(_, t)| t.name.as_deref() == Some("Frame"))
        .expect("Frame in frame.wgsl");
    assert_eq!(
        layouter[handle].size as usize,
        std::mem::size_of::<FrameUniforms>()
    );
}

#[test]
fn view_constants_in_wgsl_are_the_rust_enum() {
    use terrain::gpu::uniforms::View;
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
