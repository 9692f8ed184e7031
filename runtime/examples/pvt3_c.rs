//! The C ABI as a static library built by `cargo test` itself (which builds examples but not the
//! crate's own staticlib), so the C example test links against the code under test.
pub use pvt3_runtime::ffi::*;
