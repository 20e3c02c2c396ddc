"""Environment layer: a robot arm driven by relative TCP commands, in any domain's scene."""
