//! e2e

mod vkf;
