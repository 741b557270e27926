//! # plot: PNG line plots for results and the validation report
//!
//! (Being written: see issue 7 and issue 8.)
