//! The renderer's table of passes, generated from the registry (`registry::for_each_pass!`):
//! one field per registered pass, built, rebuilt and looked up by the same list.

use crate::render::error::RenderError;
use crate::render::pass::{PassContext, Rebuild, RegisteredPass, RenderPass};
use crate::render::plan::Pass;

/// Declares `Passes` from the registry's list.
macro_rules! pass_table {
    ($( $(#[doc = $doc:literal])* $(#[cfg($cfg:meta)])? $variant:ident = $name:literal : $module:ident :: $ty:ident, )*) => {
        /// Every registered pass this renderer built (`None` where it has none, as the tone map
        /// of a host target), one field per line of the registry, named after its module.
        pub(super) struct Passes {
            $( $(#[doc = $doc])* $(#[cfg($cfg)])? pub(super) $module: Option<crate::render::$module::$ty>, )*
        }

        impl Passes {
            /// Every registered pass built for `context`.
            pub(super) fn build(context: &PassContext) -> Result<Passes, RenderError> {
                Ok(Passes {
                    $( $(#[cfg($cfg)])? $module: <crate::render::$module::$ty as RegisteredPass>::build(context)?, )*
                })
            }

            /// The passes that `event` affects built anew for `context`, the others kept. All
            /// are built before any is replaced, so an error leaves every pass as it was.
            pub(super) fn rebuild(&mut self, context: &PassContext, event: Rebuild) -> Result<(), RenderError> {
                $(
                    $(#[cfg($cfg)])?
                    let $module = match <crate::render::$module::$ty as RegisteredPass>::REBUILT_ON.contains(&event) {
                        true => Some(<crate::render::$module::$ty as RegisteredPass>::build(context)?),
                        false => None,
                    };
                )*
                $(
                    $(#[cfg($cfg)])?
                    if let Some(pass) = $module {
                        self.$module = pass;
                    }
                )*
                Ok(())
            }

            /// The recorder of `pass`, if this renderer built it.
            pub(super) fn get(&self, pass: Pass) -> Option<&dyn RenderPass> {
                match pass {
                    $( $(#[cfg($cfg)])? Pass::$variant => self.$module.as_ref().map(|p| p as &dyn RenderPass), )*
                }
            }
        }
    };
}

crate::render::registry::for_each_pass!(pass_table);
