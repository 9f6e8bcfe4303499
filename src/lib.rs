//! tissue-sim: an anisotropic soft-tissue cube, simulated by a mass-spring model calibrated
//! against a linear finite-element reference (Choi, "heuristically parameterized anisotropic
//! mass-spring model").
//!
//! Data flows one way: [`material`] -> [`fem`] reference -> [`accuracy`] (cost and error tables)
//! -> [`msm`] parameters -> dynamics. [`grid`] and [`cases`] fix the benchmark's conventions
//! (`shared/spec/benchmark.md`); [`io`] writes its JSON files; [`cli`] is the command line.

pub mod accuracy;
pub mod app;
pub mod bench;
pub mod calibrate;
pub mod cases;
pub mod cli;
pub mod fem;
pub mod grid;
pub mod io;
pub mod material;
pub mod msm;
pub mod render;
pub mod reproduce;
pub mod scene;
pub mod script;
pub mod sim;
pub mod sparse;
pub mod study;
pub mod tissue;
