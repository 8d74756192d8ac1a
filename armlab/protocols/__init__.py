"""Protocols: the :class:`Protocol` interface, one package per paper's protocol, one registry.

``armlab.protocols.registry`` lists the protocols (one registration line each) and is what the
runner and the CLI ask; the interface is in :mod:`armlab.protocols.base`. See
docs/architecture.md for what a new protocol writes.
"""

from armlab.protocols.base import (
    Command,
    DiagnosisHooks,
    OutputContext,
    Protocol,
    Referee,
    Simulated,
)

__all__ = [
    "Command",
    "DiagnosisHooks",
    "OutputContext",
    "Protocol",
    "Referee",
    "Simulated",
]
