"""03 — identification: draw a synthetic campaign from a perturbed world, identify the
model from 80 % of it, and compare held-out landing errors before and after.

Run: .venv/bin/python examples/03_identify_from_a_campaign.py
"""

import numpy as np

from cell.identify import identify
from cell.model import predict_landing
from cell.params import ModelParams
from cell.synth import Campaign, default_world, draw_campaign

world = default_world()
table = draw_campaign(world, Campaign(n=400), seed=1)
rng = np.random.default_rng(0)
test = rng.random(len(table)) < 0.2
fit = identify(table.take(~test))
held = table.take(test)


def rmse(params: ModelParams) -> float:
    pred = predict_landing(held.to_batch(objects=params.objects), params.ee, strict=False)
    return float(np.sqrt(np.nanmean(np.sum((pred.xy - held.landed) ** 2, axis=1))))


print(f"{fit.iterations} iterations, {fit.seconds:.1f} s")
print(
    f"held-out landing RMSE: reference parameters {rmse(ModelParams()):.3f} m, "
    f"identified {rmse(fit.params):.3f} m"
)
