"""Signal processing: Allan deviation and (later) decomposition, entropy and filtering."""
