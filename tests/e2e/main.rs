//! End-to-end tests of the built `loupe` binary. One test binary, one
//! harness (`loupe_tests`), a module per subcommand.

mod browser;
mod budget_preview;
mod check;
mod denoise;
mod golden;
mod images;
mod materials;
mod materials_api;
mod no_adapter;
mod pixel_history;
mod printf;
mod protocol;
mod recipe;
mod render;
mod serve;
mod timings;
mod tradeoffs;
mod view;
