//! Typed errors. Library code returns these on bad input; it does not panic.

/// A resource that does not fit the slot the shader declares: the wrong kind, format, sample
/// type or dimension, a missing usage, a buffer smaller than the shader needs or larger than
/// the device's binding limit, an offset off its alignment.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "stage {stage}, entry point `{entry_point}`, binding `{binding}` (@group({group}) @binding({index})): {problem}"
)]
pub struct BindingError {
    /// The stage (`room::name`).
    pub stage: &'static str,
    /// The entry point whose resources were bound.
    pub entry_point: &'static str,
    /// The shader's name for the binding.
    pub binding: &'static str,
    /// Its `@group`.
    pub group: u32,
    /// Its `@binding`.
    pub index: u32,
    /// What is wrong with the resource given.
    pub problem: String,
}

/// Every error fieldkit returns. Each names the stage and what was wrong.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// No adapter was found; the message says how to get one.
    #[error(
        "no GPU adapter found ({detail}). Install a Vulkan driver: on Debian/Ubuntu \
         `apt-get install mesa-vulkan-drivers` gives the software rasteriser lavapipe (llvmpipe)"
    )]
    NoAdapter {
        /// Which adapters were looked for and found.
        detail: String,
    },
    /// The adapter refused the device.
    #[error("could not open a device on {adapter}: {detail}")]
    Device {
        /// The adapter asked.
        adapter: String,
        /// What it said.
        detail: String,
    },
    /// A resource that does not fit the slot the shader declares.
    #[error(transparent)]
    Binding(#[from] BindingError),
    /// A wgpu validation or out-of-memory error, captured by an error scope.
    #[error("stage {stage}: wgpu reported: {message}")]
    Wgpu {
        /// The stage that was being created or run.
        stage: &'static str,
        /// wgpu's message.
        message: String,
    },
    /// The device was lost while a stage ran.
    #[error("device lost while running {stage}")]
    DeviceLost {
        /// The stage that was running.
        stage: &'static str,
    },
    /// A parameter is NaN, negative, zero where it must not be, or otherwise unusable.
    #[error("stage {stage}: invalid input: {what}")]
    Invalid {
        /// The stage refusing it.
        stage: &'static str,
        /// Which parameter, and why.
        what: String,
    },
    /// A size is zero or past what the device (or the encoding) supports.
    #[error("stage {stage}: {what} is {got}, must be between 1 and {max}")]
    Size {
        /// The stage refusing it.
        stage: &'static str,
        /// Which size.
        what: &'static str,
        /// The size given.
        got: u64,
        /// The largest allowed.
        max: u64,
    },
    /// A texture of a format the stage does not read.
    #[error(
        "stage {stage}: texture format {format:?} is not supported here (use one of {supported})"
    )]
    Format {
        /// The stage refusing it.
        stage: &'static str,
        /// The format given.
        format: wgpu::TextureFormat,
        /// The formats it takes.
        supported: &'static str,
    },
    /// The device lacks a feature the stage's shader needs (binding arrays, immediates): ask
    /// for it when the device is made.
    #[error("stage {stage}: the device lacks {what}; request it in the device descriptor")]
    Unsupported {
        /// The stage refusing to run.
        stage: &'static str,
        /// What is missing.
        what: String,
    },
    /// Hot reload refused a stage's file: it no longer links or validates, or its interface
    /// differs from the bindings compiled into the app (feature `hot-reload`).
    #[error("stage {stage}: reload refused: {what}")]
    Reload {
        /// The stage being reloaded.
        stage: &'static str,
        /// Why, with file:line:col for a shader error.
        what: String,
    },
    /// Mapping a buffer for readback failed.
    #[error("readback failed: {0}")]
    Readback(String),
}

impl Error {
    /// [`Error::Invalid`]: bad input to `stage`, `what` saying what was wrong.
    pub fn invalid(stage: &'static str, what: impl Into<String>) -> Self {
        Error::Invalid {
            stage,
            what: what.into(),
        }
    }
}
