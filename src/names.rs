//! The names a scene file and the command line spell a choice with: one table per enum gives
//! its `ALL`, `name`, case-insensitive `FromStr` (whose error lists every name) and `Display`.

/// `"a, b or c"`: the names a parse error offers.
pub(crate) fn listed(names: &[&str]) -> String {
    match names {
        [] => String::new(),
        [one] => (*one).to_string(),
        [rest @ .., last] => format!("{} or {last}", rest.join(", ")),
    }
}

/// `named_choices!(Type, "what it is", { Variant => "name", ... })`: `Type::ALL` (every variant,
/// in the table's order), `Type::name`, `FromStr` and `Display` from one table, so a variant's
/// name is written once.
macro_rules! named_choices {
    ($ty:ident, $what:literal, { $($variant:ident => $name:literal),+ $(,)? }) => {
        impl $ty {
            /// Every choice, in the order the command line lists them.
            pub const ALL: [$ty; [$($name),+].len()] = [$($ty::$variant),+];

            /// The name used in scene files and on the command line.
            pub fn name(self) -> &'static str {
                match self {
                    $($ty::$variant => $name,)+
                }
            }
        }

        impl std::str::FromStr for $ty {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, Self::Err> {
                $ty::ALL.into_iter().find(|m| m.name().eq_ignore_ascii_case(s)).ok_or_else(|| {
                    format!("unknown {} `{s}` (expected {})", $what, $crate::names::listed(&[$($name),+]))
                })
            }
        }

        impl std::fmt::Display for $ty {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.pad(self.name())
            }
        }
    };
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_parse_error_lists_every_name_and_a_name_parses_back_in_any_case() {
        use crate::scene::{GatherMode, SplatVisibility, TransportMode};
        assert_eq!(super::listed(&["a", "b", "c"]), "a, b or c");
        let err = "x".parse::<SplatVisibility>().unwrap_err();
        assert_eq!(err, "unknown splat visibility `x` (expected hybrid, rays or shadow_maps)");
        for m in GatherMode::ALL {
            assert_eq!(m.name().to_uppercase().parse::<GatherMode>(), Ok(m));
        }
        for m in TransportMode::ALL {
            assert_eq!(m.to_string().parse::<TransportMode>(), Ok(m));
        }
        for m in crate::sampling::Method::ALL {
            assert_eq!(m.name().parse::<crate::sampling::Method>(), Ok(m));
        }
    }
}
