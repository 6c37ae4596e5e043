//! (De)serialisation of boxed kernels (`serde` feature): a `Box<dyn Kernel>` is written as the
//! built-in kernel it holds, tagged with its type's name (`{"Rbf": {…}}`), and read back as that
//! kernel. Kernels of other types cannot be serialised: a trait object does not say how to
//! rebuild it, so the set is closed (a user kernel is an error naming it).

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::{
    Constant, Constrained, Matern32, Matern52, Periodic, Product, Rbf, RbfArd, Scaled, Sum, White,
};
use crate::kernel::Kernel;

/// Declares the tagged forms of the built-in kernels: borrowed for writing, owned for reading,
/// with the same variants in the same order (binary formats number them).
macro_rules! built_in {
    ($($name:ident),+ $(,)?) => {
        /// A built-in kernel behind a `&dyn Kernel`, as written.
        #[derive(Serialize)]
        #[serde(rename = "Kernel")]
        enum KernelRef<'a> {
            $($name(&'a $name),)+
        }

        /// A built-in kernel, as read.
        #[derive(Deserialize)]
        #[serde(rename = "Kernel")]
        enum KernelOwned {
            $($name($name),)+
        }

        /// The built-in kernel `k` is, if it is one.
        fn to_ref(k: &dyn Kernel) -> Option<KernelRef<'_>> {
            let any = k.as_any();
            $(
                if let Some(k) = any.downcast_ref::<$name>() {
                    return Some(KernelRef::$name(k));
                }
            )+
            None
        }

        impl KernelOwned {
            fn boxed(self) -> Box<dyn Kernel> {
                match self {
                    $(KernelOwned::$name(k) => Box::new(k),)+
                }
            }
        }

        /// The names of the built-in kernels, for error messages.
        const BUILT_IN: &str = concat!($(stringify!($name), " "),+);
    };
}

built_in!(
    Rbf,
    RbfArd,
    Matern32,
    Matern52,
    Periodic,
    White,
    Constant,
    Scaled,
    Sum,
    Product,
    Constrained,
);

/// Writes a built-in kernel tagged with its type's name, e.g.
/// `{"Rbf": {"variance": 1.0, "length_scale": 2.0}}` in JSON; combinators nest their parts
/// the same way.
///
/// # Errors
/// A serialiser error naming the kernel if it is not one of the crate's kernels.
impl Serialize for dyn Kernel + '_ {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        match to_ref(self) {
            Some(k) => k.serialize(serializer),
            None => Err(serde::ser::Error::custom(format_args!(
                "kernel {self:?} cannot be serialised: only the built-in kernels can ({})",
                BUILT_IN.trim_end()
            ))),
        }
    }
}

/// Reads a kernel written by `dyn Kernel`'s `Serialize`, checking its hyperparameters with the
/// kernel's constructor.
impl<'de> Deserialize<'de> for Box<dyn Kernel> {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        KernelOwned::deserialize(deserializer).map(KernelOwned::boxed)
    }
}
