"""Looking at results: 2D figures, off-screen 3D renders and the drawable geometry they share."""
