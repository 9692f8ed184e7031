//! The runtime's own kernels for x86-64: [`small_products`], in AVX-512 and in AVX2 with FMA,
//! chosen at run time by what the CPU has. Other architectures run tract's kernels (tract-linalg
//! brings NEON kernels for aarch64); a kernel of the runtime's own for one of them goes in a
//! module beside this one, named for its architecture, as tract-linalg lays out its own.

pub(crate) mod small_products;
