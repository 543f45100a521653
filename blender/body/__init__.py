"""D'Apuzzo's body model built on the armature (issue 29)."""
