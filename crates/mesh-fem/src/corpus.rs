//! TODO-module (filled by the mesh I/O work).
