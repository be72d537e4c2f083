"""mapcheck: the analytic near-grazing maps of Molenaar, de Weger & van de Water (2001)."""
from .exact import ExactOscillator

__all__ = ["ExactOscillator"]
