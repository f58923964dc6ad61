//! Small dense linear-algebra helpers.
