"""The state-to-skill classifier: data, training, the model and its metrics."""
