//! The engines csm-lab reproduces, one file each, and the registry that lists them: the
//! `engines!` line below is an engine's only mention outside its own file.

use serde::Serialize;

use super::{DynEngine, Engine, KnobsOf};

/// Declares the engine modules and the registry: [`PresetName`], [`Knobs`] and [`ENGINES`] list
/// them in this order (the order reports use).
macro_rules! engines {
    ($($module:ident :: $engine:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// The implementations csm-lab reproduces.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
        pub enum PresetName {
            $($engine,)*
        }

        const COUNT: usize = [$(stringify!($engine)),*].len();

        impl PresetName {
            pub const ALL: [PresetName; COUNT] = [$(PresetName::$engine),*];

            /// The engine's rules.
            pub fn engine(self) -> &'static dyn DynEngine {
                ENGINES[self as usize]
            }
        }

        /// Every engine, in [`PresetName`] order.
        pub(crate) static ENGINES: [&dyn DynEngine; COUNT] = [$(&$module::$engine),*];

        /// A preset's engine knobs, resolved (defaults applied, validated).
        #[derive(Debug, Clone, PartialEq)]
        pub enum Knobs {
            $($engine(<$module::$engine as Engine>::Knobs),)*
        }

        impl Knobs {
            pub(crate) fn name(&self) -> PresetName {
                match self {
                    $(Knobs::$engine(_) => PresetName::$engine,)*
                }
            }
        }

        impl Serialize for Knobs {
            fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
                match self {
                    $(Knobs::$engine(k) => s.serialize_newtype_variant(
                        "Knobs",
                        PresetName::$engine as u32,
                        <$module::$engine as Engine>::NAME,
                        k,
                    ),)*
                }
            }
        }

        $(
            impl KnobsOf for $module::$engine {
                fn get(k: &Knobs) -> Option<&Self::Knobs> {
                    match k {
                        Knobs::$engine(x) => Some(x),
                        #[allow(unreachable_patterns)]
                        _ => None,
                    }
                }

                fn get_mut(k: &mut Knobs) -> Option<&mut Self::Knobs> {
                    match k {
                        Knobs::$engine(x) => Some(x),
                        #[allow(unreachable_patterns)]
                        _ => None,
                    }
                }

                fn wrap(k: Self::Knobs) -> Knobs {
                    Knobs::$engine(k)
                }
            }
        )*
    };
}

engines! {
    dart::Dart,
    threejs::Threejs,
    unity_sample::UnitySample,
    eevee::Eevee,
    learnopengl::LearnOpenGl,
    bevy::Bevy,
    godot::Godot,
    unreal::Unreal,
    unity::Unity,
    unity_urp::UnityUrp,
    filament::Filament,
}
