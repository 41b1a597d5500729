//! Log formats of gsens.
