"""Tests of what every study is built from (src/designkit/studies/core)."""
