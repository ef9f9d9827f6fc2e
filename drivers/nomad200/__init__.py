"""Nomad 200 host serial protocol: a pure codec (``codec``) and SI unit helpers (``units``)."""
