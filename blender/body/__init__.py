"""D'Apuzzo's body model built on the armature: one metaball ellipsoid per bone."""
