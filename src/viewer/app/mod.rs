//! The viewer application.

pub mod input;
