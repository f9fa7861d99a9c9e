//! The CPU reference renderer (in progress).
