//! superelement
