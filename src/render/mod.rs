//! The bundled spectral path tracer for the validation box (issue 4).
