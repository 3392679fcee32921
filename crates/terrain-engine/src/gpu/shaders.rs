//! The shader import step: each pass's WGSL file with its `#import name` lines replaced by
//! `shaders/shared/name.wgsl` (or, for `#import constants`, the constants WGSL shares with Rust,
//! written from the Rust values), and `#ifdef FLAG` / `#else` / `#endif` blocks kept or dropped by the
//! variant's flags. That is all the preprocessing there is. A variant's flags are one [`Key`],
//! derived per scene and mode in one place (`lod::shader_key`).
//!
//! Rules: an import is included once per shader; flags nest; an unknown import or an unbalanced
//! block is an error naming the file and line (tests validate every variant with naga).
//! Rejected alternative: override constants for variants. A loop bounded by `octaves = 0` still
//! ships the noise code to the driver; dropping the text is what "no noise code" means.

use crate::error::{Error, Result};
use std::sync::LazyLock;

/// `#import constants`: the values the WGSL shares with the CPU, written from the Rust
/// constants, so that the two sides cannot drift apart.
static CONSTANTS: LazyLock<String> = LazyLock::new(|| {
    use crate::light;
    let f = |v: f64| format!("{:?}", v as f32);
    let [r, g, b] = light::RAYLEIGH.map(f);
    [
        "// Written by src/gpu/shaders.rs from the Rust constants of the same names.".into(),
        format!("const MAX_OCTAVES: u32 = {}u;", crate::scene::MAX_OCTAVES),
        format!("const RAYLEIGH: vec3<f32> = vec3<f32>({r}, {g}, {b});"),
        format!(
            "const RAYLEIGH_SCALE_M: f32 = {};",
            f(light::RAYLEIGH_SCALE_M)
        ),
        format!("const HAZE_ALBEDO: f32 = {};", f(light::HAZE_ALBEDO)),
        format!("const MIE_G: f32 = {};", f(light::MIE_G)),
        format!("const MULTIPLE: f32 = {};", f(light::MULTIPLE)),
        format!("const STEPS: i32 = {};", light::STEPS),
        format!("const TOP_M: f32 = {};", f(light::TOP_M)),
        format!("const FAR_M: f32 = {};", f(light::FAR_M)),
    ]
    .into_iter()
    .chain(surface_classes())
    .collect::<Vec<_>>()
    .join("\n")
});

/// The surface view's classes (`surface::SURFACE_CLASSES`): `CLASS_<NAME>` each its index,
/// `CLASS_COUNT`, and `CLASS_COLOURS`, their colours in order.
fn surface_classes() -> Vec<String> {
    let classes = &crate::surface::SURFACE_CLASSES;
    let colours: Vec<String> = classes
        .iter()
        .map(|(_, [r, g, b])| format!("vec3<f32>({r:?}, {g:?}, {b:?})"))
        .collect();
    let n = classes.len();
    classes
        .iter()
        .enumerate()
        .map(|(i, (name, _))| format!("const CLASS_{}: u32 = {i}u;", name.to_uppercase()))
        .chain([
            format!("const CLASS_COUNT: u32 = {n}u;"),
            format!(
                "const CLASS_COLOURS: array<vec3<f32>, {n}> = array<vec3<f32>, {n}>({});",
                colours.join(", ")
            ),
        ])
        .collect()
}

const SHARED: [(&str, &str); 9] = [
    ("frame", include_str!("../../shaders/shared/frame.wgsl")),
    ("noise", include_str!("../../shaders/shared/noise.wgsl")),
    ("atlas", include_str!("../../shaders/shared/atlas.wgsl")),
    ("shading", include_str!("../../shaders/shared/shading.wgsl")),
    ("surface", include_str!("../../shaders/shared/surface.wgsl")),
    ("sphere", include_str!("../../shaders/shared/sphere.wgsl")),
    ("raster", include_str!("../../shaders/shared/raster.wgsl")),
    ("fade", include_str!("../../shaders/shared/fade.wgsl")),
    ("work", include_str!("../../shaders/shared/work.wgsl")),
];

/// A shader variant: a set of [`FLAGS`], a bit each. One key is derived per scene and mode
/// ([`crate::lod::shader_key`]) and every pass of the scheme is composed with it; a pass ignores
/// the flags its WGSL does not test.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Key(u32);

/// The flags: a [`Key`] constant each, and their names in bit order.
macro_rules! flags {
    ($($flag:ident),* $(,)?) => {
        #[allow(non_camel_case_types, clippy::upper_case_acronyms)]
        enum Bit { $($flag),* }
        impl Key {
            $(pub const $flag: Key = Key(1 << Bit::$flag as u32);)*
        }
        /// Every flag any pass tests, for validating all variants.
        pub const FLAGS: [&str; [$(stringify!($flag)),*].len()] = [$(stringify!($flag)),*];
    };
}

flags!(
    DETAIL,
    CENTRES,
    BUMP,
    BUMP_FADE,
    NOISE,
    IMPORTANCE_VIEW,
    GEOMIPMAP,
    POSITIONS,
    PIXEL_NORMALS,
    SHADOWS,
    DETAIL_SHADOWS,
    SUPERSAMPLE,
    STREAMED,
    GRID_STREAMED,
    DEFERRED,
    FROM_BUFFERS,
    COUNT_WORK,
    SUN_MAP,
    RAMP,
    IMAGE,
    SHORE,
);

impl Key {
    pub const NONE: Key = Key(0);

    /// The key of the flags named (every name one of [`FLAGS`]).
    pub fn of(names: &[&str]) -> Key {
        Key(FLAGS
            .iter()
            .enumerate()
            .filter(|(_, f)| names.contains(f))
            .fold(0, |bits, (k, _)| bits | 1 << k))
    }

    /// Both keys' flags.
    pub const fn union(self, other: Key) -> Key {
        Key(self.0 | other.0)
    }

    /// Whether every flag of `flags` is set.
    pub const fn contains(self, flags: Key) -> bool {
        self.0 & flags.0 == flags.0
    }

    /// Whether any flag of `flags` is set.
    pub const fn any(self, flags: Key) -> bool {
        self.0 & flags.0 != 0
    }

    /// Sets `flags` where `on`.
    pub fn set(&mut self, flags: Key, on: bool) {
        if on {
            self.0 |= flags.0;
        }
    }

    /// The flags' names, for [`compose`].
    pub fn defs(self) -> Vec<&'static str> {
        FLAGS
            .iter()
            .enumerate()
            .filter(|(k, _)| self.0 & 1 << k != 0)
            .map(|(_, f)| *f)
            .collect()
    }
}

impl std::ops::BitOr for Key {
    type Output = Key;
    fn bitor(self, other: Key) -> Key {
        Key(self.0 | other.0)
    }
}

/// The combined source of pass `name`'s WGSL `source` with `flags` set.
pub fn compose(name: &str, source: &str, flags: &[&str]) -> Result<String> {
    let mut out = String::new();
    let mut imported: Vec<&str> = Vec::new();
    expand(name, source, flags, &mut imported, &mut out)?;
    Ok(out)
}

/// The flags pass `name`'s WGSL or any file it may import tests (`#ifdef`): every other flag
/// leaves its source alone, which lets the checks compose each distinct variant once.
#[cfg(test)]
pub fn tested_flags(source: &str) -> Key {
    fn walk<'a>(source: &'a str, seen: &mut Vec<&'a str>, names: &mut Vec<&'a str>) {
        for line in source.lines().map(str::trim) {
            if let Some(flag) = line.strip_prefix("#ifdef ") {
                names.push(flag.trim());
            } else if let Some(import) = line.strip_prefix("#import ") {
                let import = import.trim();
                if let Some((key, text)) = SHARED.iter().find(|(n, _)| *n == import)
                    && !seen.contains(key)
                {
                    seen.push(key);
                    walk(text, seen, names);
                }
            }
        }
    }
    let mut names = Vec::new();
    walk(source, &mut Vec::new(), &mut names);
    Key::of(&names)
}

/// Only the flags of `self` that `mask` holds too.
impl std::ops::BitAnd for Key {
    type Output = Key;
    fn bitand(self, mask: Key) -> Key {
        Key(self.0 & mask.0)
    }
}

fn expand<'a>(
    file: &str,
    source: &'a str,
    flags: &[&str],
    imported: &mut Vec<&'a str>,
    out: &mut String,
) -> Result<()> {
    // Each open block: (this block is kept, an enclosing block is kept).
    let mut stack: Vec<(bool, bool)> = Vec::new();
    let bad = |line: usize, what: &str| Error::Shader {
        file: file.to_string(),
        reason: format!("line {}: {what}", line + 1),
    };
    for (k, line) in source.lines().enumerate() {
        let trimmed = line.trim();
        let live = stack.iter().all(|&(keep, _)| keep);
        if let Some(flag) = trimmed.strip_prefix("#ifdef ") {
            stack.push((flags.contains(&flag.trim()), live));
        } else if trimmed == "#else" {
            let top = stack
                .last_mut()
                .ok_or_else(|| bad(k, "#else without #ifdef"))?;
            top.0 = !top.0;
        } else if trimmed == "#endif" {
            stack.pop().ok_or_else(|| bad(k, "#endif without #ifdef"))?;
        } else if let Some(name) = trimmed.strip_prefix("#import ") {
            if !live {
                continue;
            }
            let name = name.trim();
            let (key, text): (&'a str, &'a str) = match name {
                "constants" => ("constants", CONSTANTS.as_str()),
                _ => SHARED
                    .iter()
                    .find(|(n, _)| *n == name)
                    .copied()
                    .ok_or_else(|| bad(k, &format!("unknown import `{name}`")))?,
            };
            if !imported.contains(&key) {
                imported.push(key);
                expand(name, text, flags, imported, out)?;
            }
        } else if live {
            out.push_str(line);
            out.push('\n');
        }
    }
    if !stack.is_empty() {
        return Err(Error::Shader {
            file: file.to_string(),
            reason: "#ifdef without #endif".into(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `#import constants` holds the Rust values, as naga reads them back.
    #[test]
    fn the_shared_constants_are_the_rust_values() {
        use naga::{Expression, Literal};
        let module = naga::front::wgsl::parse_str(&CONSTANTS).unwrap();
        fn flat(module: &naga::Module, e: naga::Handle<Expression>, out: &mut Vec<f64>) {
            match &module.global_expressions[e] {
                Expression::Compose { components, .. } => {
                    components.iter().for_each(|&c| flat(module, c, out))
                }
                Expression::Literal(Literal::F32(v)) => out.push(*v as f64),
                Expression::Literal(Literal::U32(v)) => out.push(*v as f64),
                Expression::Literal(Literal::I32(v)) => out.push(*v as f64),
                other => panic!("{other:?}"),
            }
        }
        let values = |name: &str| -> Vec<f64> {
            let (_, c) = module
                .constants
                .iter()
                .find(|(_, c)| c.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("{name} missing"));
            let mut out = Vec::new();
            flat(&module, c.init, &mut out);
            out
        };
        use crate::light;
        let f32s = |v: &[f64]| v.iter().map(|&x| x as f32 as f64).collect::<Vec<_>>();
        assert_eq!(values("MAX_OCTAVES"), [crate::scene::MAX_OCTAVES as f64]);
        assert_eq!(values("RAYLEIGH"), f32s(&light::RAYLEIGH));
        assert_eq!(values("STEPS"), [light::STEPS as f64]);
        for (name, v) in [
            ("RAYLEIGH_SCALE_M", light::RAYLEIGH_SCALE_M),
            ("HAZE_ALBEDO", light::HAZE_ALBEDO),
            ("MIE_G", light::MIE_G),
            ("MULTIPLE", light::MULTIPLE),
            ("TOP_M", light::TOP_M),
            ("FAR_M", light::FAR_M),
        ] {
            assert_eq!(values(name), f32s(&[v]), "{name}");
        }
        let classes = &crate::surface::SURFACE_CLASSES;
        for (i, (name, _)) in classes.iter().enumerate() {
            let name = format!("CLASS_{}", name.to_uppercase());
            assert_eq!(values(&name), [i as f64], "{name}");
        }
        assert_eq!(values("CLASS_COUNT"), [classes.len() as f64]);
        let colours: Vec<f64> = classes.iter().flat_map(|c| c.1.map(f64::from)).collect();
        assert_eq!(values("CLASS_COLOURS"), colours);
        assert_eq!(
            module.constants.len(),
            9 + classes.len() + 2,
            "a constant without its check"
        );
    }

    #[test]
    fn a_key_names_its_flags() {
        let key = Key::NOISE | Key::DEFERRED;
        assert_eq!(key.defs(), ["NOISE", "DEFERRED"]);
        assert_eq!(Key::of(&key.defs()), key);
        assert!(key.contains(Key::NOISE) && !key.contains(Key::NOISE | Key::BUMP));
        assert!(key.any(Key::NOISE | Key::BUMP) && !key.any(Key::BUMP));
        // A bit each in the key's u32, and every flag's name round-trips to its own bit.
        assert!(FLAGS.len() <= 32, "{} flags", FLAGS.len());
        for (i, name) in FLAGS.iter().enumerate() {
            assert_eq!(Key::of(&[*name]), Key(1 << i), "{name}");
            assert_eq!(Key(1 << i).defs(), [*name]);
        }
    }
}
