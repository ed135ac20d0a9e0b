//! In-module tests of the link.
