"""Scene files: the schema of every key and its validation, loading and resolving scenes."""
