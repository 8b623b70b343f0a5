"""06 — a small sort job run from Python: one item placed, one thrown.

Run: .venv/bin/python examples/06_sort_job.py
"""

from cell.jobs import parse_job
from cell.orchestrator import Orchestrator

JOB = """
bins:
  - {id: near, position_m: [0.55, 0.30], size_m: [0.3, 0.3], rim_height_m: 0.12}
  - {id: far, position_m: [1.8, -0.4], size_m: [0.3, 0.3], rim_height_m: 0.15}
items:
  - {object: cyl70, bin: near}
  - {object: sphere55, bin: far}
"""
orch = Orchestrator(parse_job(JOB, "example.yaml"))
try:
    summary = orch.run()
finally:
    orch.close()
for r in summary.results:
    print(f"{r.object_id}: {r.action} -> {r.bin_id or 'no bin'} (error {r.landing_error_m:.3f} m)")
print(
    f"in bin {summary.in_bin}/{summary.items}, {summary.items_per_hour:.0f} items per simulated hour"
)
