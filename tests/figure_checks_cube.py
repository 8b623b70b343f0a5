"""Figure checks for docs/gap-tracks.md's fourth real set: DAIR Lab's tossed cube
(docs/figures/real_tracks.json, key "cube")."""

from __future__ import annotations

from tests.figure_quotes import close, load_json, quoted


def check_the_real_cube() -> None:
    from cell.gap.track_check import MIN_SPAN_S

    page, doc = "docs/gap-tracks.md", load_json("docs/figures/real_tracks.json")
    cb = doc["cube"]
    n, kg, side, hz, med, usable, span, share, speed, rms = quoted(
        page,
        r"ContactNets data, (\d+) tosses of a ([\d.]+) kg cube ([\d.]+) m a side, tracked by "
        r"AprilTags at (\d+) Hz .*? a median (\d+) samples; .*? on the (\d+) tosses of ([\d.]+) s "
        r"or more .*? the drag, ([\d.]+) of gravity at ([\d.]+) m/s, left out\) fits within "
        r"([\d.]+) mm RMS",
    )
    assert (int(n), int(usable)) == (cb["tosses"], cb["tosses_usable"])
    assert (float(kg), float(side), float(hz)) == (cb["mass_kg"], cb["side_m"], cb["rate_hz"])
    assert float(med) == cb["samples_median"] and float(span) == MIN_SPAN_S
    close(share, cb["drag_over_gravity"], 3)
    close(speed, cb["speed_mps_median"], 2)
    close(rms, 1000 * cb["second_rms_m"], 2)
    gh, g, lo, hi, rate, base = quoted(
        page,
        r"a horizontal part of ([\d.]+) m/s²\) and the cube coming down at ([\d.]+) g "
        r"\(([\d.]+)–([\d.]+) g but for .*? frames ([\d.]+) Hz apart rather than (\d+) Hz",
    )
    close(gh, cb["second_horizontal_g_mps2"], 3)
    close(g, cb["second_g_ratio_median"], 3)
    close(lo, cb["second_g_ratio_p10_p90"][0], 3)
    close(hi, cb["second_g_ratio_p10_p90"][1], 3)
    close(rate, cb["implied_rate_hz"], 1)
    assert float(base) == cb["rate_hz"]
    gc, rc, short, k = quoted(
        page,
        r"cell's track fit finds ([\d.]+) g, the tracks fitted within ([\d.]+) mm RMS, and "
        r"names the (\d+) shorter tosses .*? On (\d+) tosses `cell gap`",
    )
    close(gc, cb["cell_g_ratio"], 3)
    close(rc, 1000 * cb["cell_fit_rms_m"], 2)
    assert int(short) == cb["tosses"] - cb["tosses_usable"] and cb["unusable"] == 0
    gap = cb["gap"]
    assert int(k) == gap["tracks"]["tracked"] and gap["where"]["phase"] == "measurement"
    ga, se, scale, held, after, floor = quoted(
        page,
        r"\(apparent gravity ([\d.]+) g, standard error ([\d.]+); .*? scale of ([\d.]+) the "
        r"landings ask for, .*? held-out ([\d.]+) m, ([\d.]+) m after, against a noise floor "
        r"of ([\d.]+) m",
    )
    close(ga, gap["tracks"]["g_ratio"], 3)
    close(se, gap["tracks"]["g_ratio_se"], 3)
    ts = next(c for c in gap["candidates"] if c["effect"] == "tracking_scale")
    assert ts["refused"] and "disagrees" in ts["refused"]
    close(scale, ts["params"]["scale_factor"], 3)
    assert gap["verdict"]["effects"] == ["bounce"] and gap["verdict"]["laws"] == {
        "bounce": "friction"
    }
    close(held, gap["baseline"]["heldout_rmse_m"], 4)
    close(after, gap["verdict"]["heldout_rmse_m"], 4)
    close(floor, gap["noise_floor_m"], 4)
