//! Kernels built from other kernels: a constant times a kernel, the sum and product of two
//! kernels, and a kernel with hyperparameters held or bounded anew.

use crate::error::{GpError, Result};
use crate::kernel::{Kernel, Positive, check_count, check_log, default_log_bounds};

/// The dimension two kernels agree on, if any.
fn joint_dim(k1: &dyn Kernel, k2: &dyn Kernel) -> Result<Option<usize>> {
    match (k1.dim(), k2.dim()) {
        (Some(expected), Some(found)) if expected != found => {
            Err(GpError::DimensionMismatch { expected, found })
        }
        (d1, d2) => Ok(d1.or(d2)),
    }
}

/// Names of `k` prefixed by `prefix`.
fn prefixed(prefix: &str, k: &dyn Kernel) -> impl Iterator<Item = String> {
    k.param_names()
        .into_iter()
        .map(move |n| format!("{prefix}{n}"))
}

/// A constant times a kernel: `k(a, b) = c · inner(a, b)`, hyperparameters
/// `[log c, inner's…]`; the inner kernel's names are prefixed `k__`.
///
/// scikit-learn: `ConstantKernel(constant_value=c) * inner`.
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "ScaledFields", try_from = "ScaledFields")
)]
pub struct Scaled {
    c: Positive,
    inner: Box<dyn Kernel>,
}

impl Scaled {
    /// `c · inner`.
    ///
    /// # Errors
    /// [`GpError::InvalidHyperparameter`] unless `c` is finite and > 0.
    pub fn new(c: f64, inner: Box<dyn Kernel>) -> Result<Self> {
        Ok(Self {
            c: Positive::new("constant_value", c)?,
            inner,
        })
    }
    /// The constant c.
    pub fn constant_value(&self) -> f64 {
        self.c.value
    }
    /// The scaled kernel.
    pub fn inner(&self) -> &dyn Kernel {
        self.inner.as_ref()
    }
}

/// The fields of a [`Scaled`] kernel as (de)serialised; deserialising checks them with
/// [`Scaled::new`] (and the inner kernel's own rules).
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct ScaledFields {
    constant_value: f64,
    inner: Box<dyn Kernel>,
}

#[cfg(feature = "serde")]
impl From<Scaled> for ScaledFields {
    fn from(k: Scaled) -> Self {
        Self {
            constant_value: k.c.value,
            inner: k.inner,
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<ScaledFields> for Scaled {
    type Error = GpError;
    fn try_from(f: ScaledFields) -> Result<Self> {
        Self::new(f.constant_value, f.inner)
    }
}

impl Kernel for Scaled {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        self.c.value * self.inner.value(a, b)
    }
    fn log_params(&self) -> Vec<f64> {
        let mut p = vec![self.c.log];
        p.extend(self.inner.log_params());
        p
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(self.n_params(), p)?;
        let log_c = check_log("constant_value", p[0])?;
        // The inner kernel's set is all-or-nothing, so setting c after it keeps ours so too.
        self.inner.set_log_params(&p[1..])?;
        self.c = Positive::from_log(log_c);
        Ok(())
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        let mut b = vec![default_log_bounds()];
        b.extend(self.inner.log_bounds());
        b
    }
    fn param_names(&self) -> Vec<String> {
        let mut n = vec!["constant_value".to_owned()];
        n.extend(prefixed("k__", self.inner.as_ref()));
        n
    }
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        let c = self.c.value;
        let (head, tail) = out.split_at_mut(1);
        self.inner.gradient(a, b, tail);
        head[0] = c * self.inner.value(a, b);
        for g in tail {
            *g *= c;
        }
    }
    fn dim(&self) -> Option<usize> {
        self.inner.dim()
    }
    fn scale_param(&self) -> Option<usize> {
        Some(0)
    }
    fn n_params(&self) -> usize {
        1 + self.inner.n_params()
    }
}

/// The fields of a [`Sum`] or [`Product`] as (de)serialised; deserialising checks them with
/// their `new` (and each kernel's own rules).
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct BinaryFields {
    k1: Box<dyn Kernel>,
    k2: Box<dyn Kernel>,
}

/// Defines a binary combinator of two boxed kernels.
macro_rules! binary {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Debug, Clone)]
        #[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
        #[cfg_attr(feature = "serde", serde(into = "BinaryFields", try_from = "BinaryFields"))]
        pub struct $name {
            k1: Box<dyn Kernel>,
            k2: Box<dyn Kernel>,
            /// `k1.n_params()`, cached.
            n1: usize,
        }

        #[cfg(feature = "serde")]
        impl From<$name> for BinaryFields {
            fn from(k: $name) -> Self {
                Self { k1: k.k1, k2: k.k2 }
            }
        }

        #[cfg(feature = "serde")]
        impl TryFrom<BinaryFields> for $name {
            type Error = GpError;
            fn try_from(f: BinaryFields) -> Result<Self> {
                Self::new(f.k1, f.k2)
            }
        }

        impl $name {
            /// The combination of `k1` and `k2`.
            ///
            /// # Errors
            /// [`GpError::DimensionMismatch`] if both kernels require a dimension and they
            /// differ.
            pub fn new(k1: Box<dyn Kernel>, k2: Box<dyn Kernel>) -> Result<Self> {
                joint_dim(k1.as_ref(), k2.as_ref())?;
                let n1 = k1.n_params();
                Ok(Self { k1, k2, n1 })
            }
            /// The first kernel (its hyperparameters come first).
            pub fn k1(&self) -> &dyn Kernel {
                self.k1.as_ref()
            }
            /// The second kernel.
            pub fn k2(&self) -> &dyn Kernel {
                self.k2.as_ref()
            }
        }

        impl Kernel for $name {
            fn value(&self, a: &[f64], b: &[f64]) -> f64 {
                Self::combine(self.k1.value(a, b), self.k2.value(a, b))
            }
            fn log_params(&self) -> Vec<f64> {
                let mut p = self.k1.log_params();
                p.extend(self.k2.log_params());
                p
            }
            fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
                check_count(self.n_params(), p)?;
                let (p1, p2) = p.split_at(self.n1);
                // Set copies so that a refusal by k2 leaves k1 unchanged too.
                let mut k1 = self.k1.clone();
                let mut k2 = self.k2.clone();
                k1.set_log_params(p1)?;
                k2.set_log_params(p2)?;
                self.k1 = k1;
                self.k2 = k2;
                Ok(())
            }
            fn log_bounds(&self) -> Vec<(f64, f64)> {
                let mut b = self.k1.log_bounds();
                b.extend(self.k2.log_bounds());
                b
            }
            fn param_names(&self) -> Vec<String> {
                prefixed("k1__", self.k1.as_ref())
                    .chain(prefixed("k2__", self.k2.as_ref()))
                    .collect()
            }
            fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
                let (g1, g2) = out.split_at_mut(self.n1);
                self.k1.gradient(a, b, g1);
                self.k2.gradient(a, b, g2);
                Self::chain(self.k1.value(a, b), self.k2.value(a, b), g1, g2);
            }
            fn dim(&self) -> Option<usize> {
                self.k1.dim().or(self.k2.dim())
            }
            fn scale_param(&self) -> Option<usize> {
                Self::scale(self.k1.as_ref(), self.k2.as_ref(), self.n1)
            }
            fn n_params(&self) -> usize {
                self.n1 + self.k2.n_params()
            }
        }
    };
}

binary! {
    /// The sum `k(a, b) = k1(a, b) + k2(a, b)`; hyperparameters are k1's followed by k2's,
    /// named with the prefixes `k1__` and `k2__` (scikit-learn's `Sum`, `k1 + k2`).
    Sum
}

binary! {
    /// The product `k(a, b) = k1(a, b) · k2(a, b)`; hyperparameters are k1's followed by
    /// k2's, named with the prefixes `k1__` and `k2__` (scikit-learn's `Product`, `k1 * k2`).
    Product
}

impl Sum {
    /// A sum has no hyperparameter that scales all of it.
    fn scale(_k1: &dyn Kernel, _k2: &dyn Kernel, _n1: usize) -> Option<usize> {
        None
    }
    fn combine(v1: f64, v2: f64) -> f64 {
        v1 + v2
    }
    /// ∂(k1 + k2) = ∂k1 and ∂k2: nothing to do.
    fn chain(_v1: f64, _v2: f64, _g1: &mut [f64], _g2: &mut [f64]) {}
}

impl Product {
    /// A scale of either factor scales the product.
    fn scale(k1: &dyn Kernel, k2: &dyn Kernel, n1: usize) -> Option<usize> {
        k1.scale_param()
            .or_else(|| k2.scale_param().map(|j| n1 + j))
    }
    fn combine(v1: f64, v2: f64) -> f64 {
        v1 * v2
    }
    /// ∂(k1 k2) = k2 ∂k1 and k1 ∂k2.
    fn chain(v1: f64, v2: f64, g1: &mut [f64], g2: &mut [f64]) {
        for g in g1 {
            *g *= v2;
        }
        for g in g2 {
            *g *= v1;
        }
    }
}

/// A kernel with hyperparameters held at their current values or bounded anew: optimisers
/// see, set and differentiate only the free ones, within their bounds (scikit-learn:
/// `bounds="fixed"`, or `(low, high)`, on a hyperparameter). The free ones keep the inner
/// kernel's order and names.
///
/// ```
/// use haunts_gp::{Constrained, Kernel, Rbf};
/// // σ² = 1 held, ℓ left to the optimiser between 0.5 and 20.
/// let mut k = Constrained::new(Box::new(Rbf::new(1.0, 2.0)?))
///     .hold("variance")?
///     .bound("length_scale", 0.5, 20.0)?;
/// assert_eq!(k.param_names(), ["length_scale"]);
/// assert_eq!(k.log_bounds(), [(0.5f64.ln(), 20f64.ln())]);
/// k.set_log_params(&[3.0f64.ln()])?;
/// assert!((k.value(&[0.0], &[3.0]) - (-0.5f64).exp()).abs() < 1e-12);
/// assert!(Constrained::new(Box::new(Rbf::new(1.0, 2.0)?)).hold("lengthscale").is_err());
/// # Ok::<(), haunts_gp::GpError>(())
/// ```
#[derive(Debug, Clone)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(
    feature = "serde",
    serde(into = "ConstrainedFields", try_from = "ConstrainedFields")
)]
pub struct Constrained {
    inner: Box<dyn Kernel>,
    /// Per inner hyperparameter: free (seen by optimisers) or held.
    free: Vec<bool>,
    /// Per inner hyperparameter: its bounds (natural values as given, to write them back).
    bounds: Vec<(Positive, Positive)>,
    n_free: usize,
}

/// The fields of a [`Constrained`] kernel as (de)serialised: the inner kernel, the names of
/// the held hyperparameters and the bounds (natural units) that differ from the inner
/// kernel's own. Deserialising replays [`Constrained::new`], [`Constrained::hold`] and
/// [`Constrained::bound`], so unknown names and bad bounds are refused as they are there.
#[cfg(feature = "serde")]
#[derive(serde::Serialize, serde::Deserialize)]
struct ConstrainedFields {
    inner: Box<dyn Kernel>,
    #[serde(default)]
    held: Vec<String>,
    #[serde(default)]
    bounds: std::collections::BTreeMap<String, (f64, f64)>,
}

#[cfg(feature = "serde")]
impl From<Constrained> for ConstrainedFields {
    fn from(k: Constrained) -> Self {
        let names = k.inner.param_names();
        let own = k.inner.log_bounds();
        let held = names
            .iter()
            .zip(&k.free)
            .filter(|(_, free)| !**free)
            .map(|(n, _)| n.clone())
            .collect();
        let bounds = names
            .into_iter()
            .zip(k.bounds.iter().zip(&own))
            .filter(|(_, ((lo, hi), o))| (lo.log, hi.log) != **o)
            .map(|(n, ((lo, hi), _))| (n, (lo.value, hi.value)))
            .collect();
        Self {
            inner: k.inner,
            held,
            bounds,
        }
    }
}

#[cfg(feature = "serde")]
impl TryFrom<ConstrainedFields> for Constrained {
    type Error = GpError;
    fn try_from(f: ConstrainedFields) -> Result<Self> {
        let mut k = Self::new(f.inner);
        for name in &f.held {
            k = k.hold(name)?;
        }
        for (name, (low, high)) in &f.bounds {
            k = k.bound(name, *low, *high)?;
        }
        Ok(k)
    }
}

/// Hyperparameters a kernel's gradient is computed for on the stack; beyond this, on the heap.
const STACK_PARAMS: usize = 16;

impl Constrained {
    /// `inner` with every hyperparameter free, within the kernel's own bounds.
    pub fn new(inner: Box<dyn Kernel>) -> Self {
        let bounds: Vec<_> = inner
            .log_bounds()
            .into_iter()
            .map(|(lo, hi)| (Positive::from_log(lo), Positive::from_log(hi)))
            .collect();
        Self {
            free: vec![true; bounds.len()],
            n_free: bounds.len(),
            bounds,
            inner,
        }
    }

    /// The index of the hyperparameter called `name` (of [`Kernel::param_names`]).
    fn index(&self, name: &str) -> Result<usize> {
        let names = self.inner.param_names();
        names
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| GpError::UnknownHyperparameter {
                name: name.to_owned(),
                known: names.clone(),
            })
    }

    /// Holds the hyperparameter called `name` at its current value.
    ///
    /// # Errors
    /// [`GpError::UnknownHyperparameter`] for a name the kernel does not have.
    pub fn hold(mut self, name: &str) -> Result<Self> {
        let i = self.index(name)?;
        if self.free[i] {
            self.free[i] = false;
            self.n_free -= 1;
        }
        Ok(self)
    }

    /// Bounds the hyperparameter called `name` to `[low, high]` (natural units) for
    /// optimisers; as in the kernels, setting a value outside them is not refused.
    ///
    /// # Errors
    /// [`GpError::UnknownHyperparameter`] for a name the kernel does not have;
    /// [`GpError::InvalidHyperparameter`] unless `0 < low <= high`, both finite.
    pub fn bound(mut self, name: &str, low: f64, high: f64) -> Result<Self> {
        let i = self.index(name)?;
        let (lo, hi) = (Positive::new(name, low)?, Positive::new(name, high)?);
        if lo.log > hi.log {
            return Err(GpError::InvalidHyperparameter {
                name: name.to_owned(),
                value: high,
                rule: "upper bound must be >= the lower bound",
            });
        }
        self.bounds[i] = (lo, hi);
        Ok(self)
    }

    /// The kernel, with every hyperparameter (held and free) at its current value.
    pub fn inner(&self) -> &dyn Kernel {
        self.inner.as_ref()
    }

    /// The free entries of `all` (one per inner hyperparameter).
    fn free_of<T: Clone>(&self, all: &[T]) -> Vec<T> {
        all.iter()
            .zip(&self.free)
            .filter(|(_, f)| **f)
            .map(|(v, _)| v.clone())
            .collect()
    }
}

impl Kernel for Constrained {
    fn value(&self, a: &[f64], b: &[f64]) -> f64 {
        self.inner.value(a, b)
    }
    fn log_params(&self) -> Vec<f64> {
        self.free_of(&self.inner.log_params())
    }
    fn set_log_params(&mut self, p: &[f64]) -> Result<()> {
        check_count(self.n_free, p)?;
        let mut all = self.inner.log_params();
        let mut given = p.iter();
        for (v, free) in all.iter_mut().zip(&self.free) {
            if *free {
                if let Some(g) = given.next() {
                    *v = *g;
                }
            }
        }
        self.inner.set_log_params(&all)
    }
    fn log_bounds(&self) -> Vec<(f64, f64)> {
        let logs: Vec<_> = self
            .bounds
            .iter()
            .map(|(lo, hi)| (lo.log, hi.log))
            .collect();
        self.free_of(&logs)
    }
    fn param_names(&self) -> Vec<String> {
        self.free_of(&self.inner.param_names())
    }
    fn gradient(&self, a: &[f64], b: &[f64], out: &mut [f64]) {
        let n = self.free.len();
        let mut stack = [0.0; STACK_PARAMS];
        let mut heap = Vec::new();
        let all: &mut [f64] = if n <= STACK_PARAMS {
            &mut stack[..n]
        } else {
            heap.resize(n, 0.0);
            &mut heap
        };
        self.inner.gradient(a, b, all);
        let kept = all.iter().zip(&self.free).filter(|(_, f)| **f);
        for (o, (g, _)) in out.iter_mut().zip(kept) {
            *o = *g;
        }
    }
    fn dim(&self) -> Option<usize> {
        self.inner.dim()
    }
    fn scale_param(&self) -> Option<usize> {
        let i = self.inner.scale_param()?;
        // Its index among the free ones, if it is free.
        self.free
            .get(i)
            .copied()
            .filter(|f| *f)
            .map(|_| self.free[..i].iter().filter(|f| **f).count())
    }
    fn n_params(&self) -> usize {
        self.n_free
    }
}
