//! [`Stages`]: a classifier cut at its seam into the spatial stage (one kept token's frames → its
//! encoding) and the temporal stage (the encodings → probabilities), each optimised for its
//! streaming shape. The classifier builds them once ([`crate::Classifier`]); sessions share them
//! (`crate::stream`).

use crate::plan::Plan;
use crate::StopRule;

/// The two stages of a classifier, each optimised for its streaming shape.
pub(crate) struct Stages {
    /// One kept token's frames `[1, tubelet, height, width, channels]` and its index → `[1, dim]`.
    pub(crate) spatial: Plan,
    /// All kept tokens' encodings `[kept, dim]` (and, where the file has the seams, the key bias
    /// `[1, 1, 1, tokens + 1]` and the window so far `[1, height, width, (channels,) frames]`)
    /// → probabilities `[1, classes]`.
    pub(crate) temporal: Plan,
    /// Whether the temporal stage reads a key bias, so that it can answer for a prefix.
    pub(crate) prefixes: bool,
    /// For a file whose spectral head streams (`FRAME_WEIGHTS`), the shape of the window the
    /// temporal stage reads, `[1, height, width, (channels,) frames]`: a session writes the kept
    /// frames it receives into one, zeros elsewhere.
    pub(crate) window: Option<Vec<usize>>,
    /// How a camera's frames become the model's (`Header::camera`).
    pub(crate) camera: Option<crate::picture::Camera>,
    /// The file's stopping rule (`Header::stop_rule`).
    pub(crate) stop_rule: Option<StopRule>,
    /// For each temporal token, its index among the kept tokens.
    pub(crate) kept_index: Vec<Option<usize>>,
    /// `[1, tubelet, height, width, channels]`
    pub(crate) token_shape: Vec<usize>,
    pub(crate) dim: usize,
    pub(crate) classes: Vec<String>,
}

impl Stages {
    /// Frames per temporal token.
    pub(crate) fn tubelet(&self) -> usize {
        self.token_shape[1]
    }
}
