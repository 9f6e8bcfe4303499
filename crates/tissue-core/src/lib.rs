//! tissue-core: an anisotropic soft-tissue cube that a program presses, drags and steps in real
//! time, with the force the material pushes back with.
//!
//! FACE_DOCS
#![cfg_attr(not(feature = "internals"), allow(dead_code, unreachable_pub))]

/// Declares the layers: public for tissue-sim's own crates (feature `internals`), else internal.
macro_rules! layers {
    ($($(#[$doc:meta])* $name:ident),* $(,)?) => {
        $(
            $(#[$doc])*
            #[cfg(feature = "internals")]
            pub mod $name;
            #[cfg(not(feature = "internals"))]
            mod $name;
        )*
    };
}

layers! {
    io,
    mechanics,
    response,
    sim,
}
