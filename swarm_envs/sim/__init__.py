"""The simulated world: platforms, arena geometry, pymunk physics with motion error, per-copy state."""
