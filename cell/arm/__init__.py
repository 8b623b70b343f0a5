"""The arm as a platform of the item loop, in parts, one concept a module.

`cell.orchestrator.Orchestrator` is the facade that puts the parts together and hands them
to the loop (`cell.loop.ItemLoop`); no module here imports the loop.
"""
