"""Tests of lab experiment 2, a comparison study (src/designkit/studies/lab2)."""
