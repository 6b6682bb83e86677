//! Live coupling over zenoh: the instance's session (`session.rs`, feature `zenoh`), its
//! CBOR payloads (`codec.rs`), the node's request handling (`node.rs`, binary
//! `sphfmu-serve`), the `zenoh.*` parameters (`settings.rs`) and the hooks that tie them to an
//! instance (`live.rs`). Without the feature only the settings and the hooks compile: the
//! parameters exist, and turning live coupling on is a named error.

pub(crate) mod live;
pub mod settings;

#[cfg(feature = "zenoh")]
pub mod codec;
#[cfg(feature = "zenoh")]
pub mod node;
#[cfg(feature = "zenoh")]
pub mod proxy;
#[cfg(feature = "zenoh")]
mod session;
#[cfg(feature = "zenoh")]
pub use session::*;
