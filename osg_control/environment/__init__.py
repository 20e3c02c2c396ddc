"""Environment layer: the Panda driven by relative TCP commands, in any domain's scene."""
