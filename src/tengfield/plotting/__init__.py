"""Plots (matplotlib, Agg). Each stage has its own module."""
