"""Randomized differential testing of the builders: generated mechanisms (``generate``), run in every
engine under the per-run rule and each non-PASS classified (``classify``); ``benchmarks/campaign.py``
runs a campaign and docs/validation.md reports it."""
