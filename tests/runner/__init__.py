"""Tests of the runner (src/designkit/runner): a spec run as the pipeline runs it, and its variants."""
