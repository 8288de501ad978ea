"""The assembled spec and its loader: what sits above the controller families.

:class:`~designkit.schema.spec.Spec` is the complete spec, whose ``controller`` section is the
discriminated union of the registered families' sections (:data:`designkit.families.FAMILIES`);
:mod:`~designkit.schema.loader` reads YAML into it with bounded parsing and key paths on every
error; :mod:`~designkit.schema.ranges_table` writes the README's table of value ranges.  The
section models these are built from are :mod:`designkit.spec`.
"""
