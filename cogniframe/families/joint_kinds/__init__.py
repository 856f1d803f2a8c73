"""The TPU joints as one family of kinds: `kind.JointKind` says what a joint kind answers (its
plan, closed form, print orientation, solid, FE support, surrogate family, assembly words), one
short module per kind subclasses it, and `kinds.KINDS` registers them."""
