// Placeholder so the build configures; replaced by the method implementation.
