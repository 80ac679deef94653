"""What a run writes: one history row per increment, fields, snapshots."""
