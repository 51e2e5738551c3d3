//! Moment-based alignment (to be written).
