"""The sim-to-real diagnosis (GAP.md): where the gap lies, which effect causes it, how far it shrinks."""
