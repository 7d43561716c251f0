//! A request's parameters, read the same way by every op: typed scalars, lengths, units and
//! tolerances, the camera and image size, and the B-Rep input. Below the ops: no op parses
//! another op's parameters, and each refusal names its parameter in backticks.

pub mod brep_input;
pub mod camera;
pub mod clustering;
pub mod lengths;
pub mod paths;
pub mod scalars;
