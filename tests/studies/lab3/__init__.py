"""Tests of lab experiment 3, a comparison study (src/designkit/studies/lab3)."""
