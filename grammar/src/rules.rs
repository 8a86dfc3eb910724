//! The pest grammar (`psl.pest`) as Rust: its parser and its rules, which the tree builder
//! (`parser`) and the syntax errors' wording (`syntax`) both read.

/// The parser pest derives from `psl.pest`.
#[derive(pest_derive::Parser)]
#[grammar = "psl.pest"]
pub struct PslParser;
