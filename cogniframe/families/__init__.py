"""The part families: one module per family, each holding its plan and closed-form estimate, its
solid and print orientation, the params key that sizes it and its hardware lines. `registry`
lists them; the part list, the part files and the tests loop over it."""
