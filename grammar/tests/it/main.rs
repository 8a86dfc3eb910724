//! The grammar's tests: each rule of `psl.pest`, and the semantic pass.

mod resolve;
mod rules;
