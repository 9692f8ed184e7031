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
    /// For a file whose spectral head streams (`FRAME_WEIGHTS`), what its temporal stage reads of
    /// the frames received.
    pub(crate) head: Option<Head>,
    /// How a camera's frames become the model's (`Header::camera`).
    pub(crate) camera: Option<crate::Camera>,
    /// The file's stopping rule (`Header::stop_rule`).
    pub(crate) stop_rule: Option<StopRule>,
    /// For each temporal token, its index among the kept tokens.
    pub(crate) kept_index: Vec<Option<usize>>,
    /// `[1, tubelet, height, width, channels]`
    pub(crate) token_shape: Vec<usize>,
    pub(crate) dim: usize,
    pub(crate) classes: Vec<String>,
}

/// What a streaming spectral head's temporal stage reads of the frames received: a session keeps
/// one buffer of [`Head::shape`], zeros where no kept frame has arrived.
pub(crate) enum Head {
    /// The window so far, `[1, height, width, (channels,) frames]`, each kept frame written in as
    /// it arrives (`pvt3_format::INPUT`: a file without the head's seams).
    Window(Vec<usize>),
    /// Each frame's features alone, `[frames, channels, features]`
    /// (`pvt3_format::HEAD_FEATURES`): `plan` computes a kept frame's row, `[1, height, width,
    /// channels]` → `[1, channels, features]`, as it arrives, so that an answer reads only them.
    Features { plan: Plan, shape: Vec<usize> },
}

impl Head {
    /// The shape of what the temporal stage reads.
    pub(crate) fn shape(&self) -> &[usize] {
        match self {
            Head::Window(shape) | Head::Features { shape, .. } => shape,
        }
    }

    /// The temporal stage's input that it is.
    pub(crate) fn input(&self) -> &'static str {
        match self {
            Head::Window(_) => pvt3_format::INPUT,
            Head::Features { .. } => pvt3_format::HEAD_FEATURES,
        }
    }
}

impl Stages {
    /// Frames per temporal token.
    pub(crate) fn tubelet(&self) -> usize {
        self.token_shape[1]
    }
}
