//! Mesh files in and out: OBJ, OFF, PLY. (to be written)
