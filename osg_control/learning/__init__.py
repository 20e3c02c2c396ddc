"""Learning layer: batched TD3+BC, checkpoints and the numpy skill policies."""
