//! Typed errors. Library code returns these on bad input; it does not panic.

/// A resource that does not fit the slot the shader declares.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error(
    "stage {stage}, entry point `{entry_point}`, binding `{binding}` (@group({group}) @binding({index})): {problem}"
)]
pub struct BindingError {
    pub stage: &'static str,
    pub entry_point: &'static str,
    pub binding: &'static str,
    pub group: u32,
    pub index: u32,
    pub problem: String,
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// No adapter was found; the message says how to get one.
    #[error(
        "no GPU adapter found ({detail}). Install a Vulkan driver: on Debian/Ubuntu \
         `apt-get install mesa-vulkan-drivers` gives the software rasteriser lavapipe (llvmpipe)"
    )]
    NoAdapter { detail: String },
    /// The adapter refused the device.
    #[error("could not open a device on {adapter}: {detail}")]
    Device { adapter: String, detail: String },
    #[error(transparent)]
    Binding(#[from] BindingError),
    /// A wgpu validation or out-of-memory error, captured by an error scope.
    #[error("stage {stage}: wgpu reported: {message}")]
    Wgpu {
        stage: &'static str,
        message: String,
    },
    /// The device was lost while a stage ran.
    #[error("device lost while running {stage}")]
    DeviceLost { stage: &'static str },
    /// A parameter is NaN, negative, zero where it must not be, or otherwise unusable.
    #[error("stage {stage}: invalid input: {what}")]
    Invalid { stage: &'static str, what: String },
    /// A size is zero or past what the device (or the encoding) supports.
    #[error("stage {stage}: {what} is {got}, must be between 1 and {max}")]
    Size {
        stage: &'static str,
        what: &'static str,
        got: u64,
        max: u64,
    },
    /// A texture of a format the stage does not read.
    #[error(
        "stage {stage}: texture format {format:?} is not supported here (use one of {supported})"
    )]
    Format {
        stage: &'static str,
        format: wgpu::TextureFormat,
        supported: &'static str,
    },
    /// Mapping a buffer for readback failed.
    #[error("readback failed: {0}")]
    Readback(String),
}
