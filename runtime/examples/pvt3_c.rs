//! The C ABI as a static and a shared library built by `cargo test` itself (which builds examples
//! but not the crate's own staticlib and cdylib), so the C example test links against the code
//! under test, installed as install.sh installs both.
pub use pvt3_runtime::ffi::*;
