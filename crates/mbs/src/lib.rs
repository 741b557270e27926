//! mbs
