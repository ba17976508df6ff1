//! Mesh file reading and field writing (filled in by the I/O work).
