"""cell: a pick-and-throw robot cell with a slingshot-like elastic end-effector."""

__version__ = "0.1.0"

__all__ = ["__version__"]
