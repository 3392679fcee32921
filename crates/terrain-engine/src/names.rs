//! Names said once: an enum whose values users type (a mode, a view, a warp method) is declared
//! with [`named_enum!`](crate::names::named_enum), which writes each variant's name in one place and
//! derives from it the scene file's spelling (serde), the command line's (through [`Named`]),
//! reports and messages (`name()`, `Display`), and the error that lists the choices.
//!
//! Rejected alternative: `#[serde(rename_all = "kebab-case")]` plus a command-line derive.
//! Each derives the same spelling by its own rule from the variant's identifier, so the two agree
//! only while the rules do, and `name()` for reports would be a third copy; the WGSL constants
//! (checked against [`ALL`](crate::gpu::uniforms::View::ALL) in `checks/shaders.rs`) need the
//! number and the name side by side anyway.

/// Declares a `Copy` enum whose variants each carry the name users type, in declaration order
/// (a variant's `as u32` is its place). Provides `ALL`, `name()`, `parse()`, `Display`, serde as
/// the name, and [`Named`].
macro_rules! named_enum {
    (
        $(#[$meta:meta])*
        $vis:vis enum $enum:ident ($what:literal) {
            $( $(#[$vmeta:meta])* $variant:ident = $name:literal ),+ $(,)?
        }
    ) => {
        $(#[$meta])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Deserialize, serde::Serialize)]
        #[serde(try_from = "String", into = "&'static str")]
        $vis enum $enum {
            $( $(#[$vmeta])* $variant ),+
        }

        impl $enum {
            /// Every value, in declaration order.
            pub const ALL: &'static [$enum] = &[$($enum::$variant),+];

            /// The name in scene files, on the command line and in reports.
            pub fn name(self) -> &'static str {
                match self {
                    $($enum::$variant => $name),+
                }
            }

            /// The value named `name`, or `None` where no variant is called that.
            pub fn parse(name: &str) -> ::std::option::Option<$enum> {
                Self::ALL.iter().copied().find(|v| v.name() == name)
            }

            /// `a, b, c`: the names, for messages.
            pub fn choices() -> String {
                Self::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", ")
            }
        }

        impl std::fmt::Display for $enum {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(self.name())
            }
        }

        impl TryFrom<String> for $enum {
            type Error = String;
            fn try_from(name: String) -> ::std::result::Result<Self, String> {
                $enum::parse(&name).ok_or_else(|| {
                    format!("unknown {} `{name}`: one of {}", $what, $enum::choices())
                })
            }
        }

        impl From<$enum> for &'static str {
            fn from(v: $enum) -> &'static str {
                v.name()
            }
        }

        impl $crate::names::Named for $enum {
            fn all() -> &'static [Self] {
                Self::ALL
            }
            fn name(self) -> &'static str {
                $enum::name(self)
            }
        }
    };
}
pub(crate) use named_enum;

/// An enum declared with `named_enum!`: its values and the name of each, for
/// a command line or a form to offer them by (the `terrain` binary's value parser).
pub trait Named: Copy + Send + Sync + 'static {
    /// Every value, in declaration order.
    fn all() -> &'static [Self];
    /// The name users type.
    fn name(self) -> &'static str;
}

#[cfg(test)]
mod tests {
    crate::names::named_enum! {
        enum Colour ("colour") {
            Red = "red",
            DeepBlue = "deep-blue",
        }
    }

    #[derive(serde::Deserialize, serde::Serialize)]
    struct Holder {
        c: Colour,
    }

    #[test]
    fn one_name_for_serde_the_command_line_and_reports() {
        use super::Named;
        let h: Holder = toml::from_str("c = \"deep-blue\"").unwrap();
        assert_eq!(h.c, Colour::DeepBlue);
        assert_eq!(toml::to_string(&h).unwrap().trim(), "c = \"deep-blue\"");
        let e = toml::from_str::<Holder>("c = \"green\"").err().unwrap();
        assert!(
            e.message()
                .contains("unknown colour `green`: one of red, deep-blue"),
            "{e}"
        );
        assert_eq!(Colour::all(), [Colour::Red, Colour::DeepBlue]);
        assert_eq!(Named::name(Colour::DeepBlue), "deep-blue");
        assert_eq!(Colour::parse("deep-blue"), Some(Colour::DeepBlue));
        assert_eq!(Colour::DeepBlue.to_string(), "deep-blue");
        assert_eq!(Colour::DeepBlue as u32, 1);
    }
}
