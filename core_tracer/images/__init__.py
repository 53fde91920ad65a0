"""Image files (EXR with the scene in the header, PNG) and the bitmap font for labels."""
