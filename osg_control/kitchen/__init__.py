"""The kitchen domain: scene, env, skill catalogue and tasks (the only place that names them)."""
