//! Simulator of a g-sensitivity calibration session.
