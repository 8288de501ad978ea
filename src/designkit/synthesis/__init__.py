"""Controller synthesis below the families: the design and law values, the closed loop, the family declaration,
and the design math several families share (one concept per module)."""
