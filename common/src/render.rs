//! Software preview renderer and contact sheets (to be written).
