"""Placeholder: the `demo` command is registered here once it exists."""

from __future__ import annotations

import argparse

__all__ = ["register"]


def register(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    """Add nothing yet."""
