//! The shader library's modules the renderer's passes share, tested on
//! the device: the BRDF's sampling, its energy compensation and random
//! numbers.

mod brdf;
mod multiscatter;
mod random;
