"""Builders: one per engine, each running a model description (nsd_core.model) with no per-mechanism code."""
