"""The checks of the figures the guide pages docs/gap-tracks.md, docs/identify_evidence.md
and docs/cli_inputs.md quote (run by tests/test_readme_figures.py): measured figures
against the JSON `make figures` writes, rules and limits against the code's constants."""

from __future__ import annotations

import math

import scipy.constants
import scipy.stats

from tests.figure_quotes import close, every, load_json, page_text, quoted


# -- docs/gap-tracks.md ----------------------------------------------------------------------
def check_the_gap_tracks_rules() -> None:
    from cell.gap.diagnose import SCALE_AGREE
    from cell.gap.run import MIN_THROWS
    from cell.gap.track_check import MAX_GAP_SHARE, MIN_SAMPLES, MIN_SPAN_S, MIN_TRAVEL_M
    from cell.gap.track_launch import DISTURBED_S, DROP_SIGMA
    from cell.gap.tracks import MAX_FIT_RMS_M
    from cell.model.params import G

    page = "docs/gap-tracks.md"
    after, sigma = quoted(page, r"samples after ([\d.]+) s are fitted first and the leading run "
                          r"of samples more than (\d+)σ off")  # fmt: skip
    assert (float(after), float(sigma)) == (DISTURBED_S, DROP_SIGMA)
    (g,) = quoted(page, r"`g_ratio` \(apparent gravity over the model's g, ([\d.]+) m/s²\)")
    assert float(g) == G
    (agree,) = quoted(page, r"apparent gravity \(within ([\d.]+) %\)")
    close(agree, 100 * SCALE_AGREE, 1)
    (n,) = quoted(page, r"a single sample, fewer than (\d+) \|")
    assert int(n) == MIN_SAMPLES
    (span,) = quoted(page, r"\| under ([\d.]+) s of samples \|")
    assert float(span) == MIN_SPAN_S
    (travel,) = quoted(page, r"does not move \(< (\d+) cm\)")
    assert float(travel) == 100 * MIN_TRAVEL_M
    assert MAX_GAP_SHARE == 0.5 and "a gap over half the track's span" in page_text(page)
    (rms,) = quoted(page, r"misses it by over (\d+) cm RMS")
    assert float(rms) == 100 * MAX_FIT_RMS_M
    (need,) = quoted(page, r"`cell gap` says it needs at least (\d+)")
    assert int(need) == MIN_THROWS
    from cell.gap.track_gravity import DOWN_COS

    (deg,) = quoted(page, r"the fit with drag finds gravity over (\d+)° from −z")
    close(str(math.cos(math.radians(float(deg)))), DOWN_COS, 9)


def check_the_real_tracks() -> None:
    from cell.model.objects import DRAG_COEFFICIENT

    page, doc = "docs/gap-tracks.md", load_json("docs/figures/real_tracks.json")
    jb = doc["jugglebot"]
    s4, s7 = jb["sessions"]["s4"], jb["sessions"]["s7"]
    hz, n, mass = quoted(page, r"motion capture at (\d+) Hz, (\d+) near-vertical throws of a "
                         r"(\d+) g ball")  # fmt: skip
    assert (float(hz), int(n), float(mass)) == (jb["rate_hz"], jb["throws"], 1000 * jb["mass_kg"])
    g, g0, k, d, cd = quoted(
        page,
        r"finds gravity ([\d.]+) × the standard ([\d.]+) m/s² in both sessions, a drag ([\d.]+) "
        r"× that of a (\d+) mm sphere of C_d ([\d.]+) in both",
    )
    for ses in (s4, s7):
        close(g, ses["second_g_ratio"], 3)
        close(k, ses["second_drag_ratio"], 1)
    assert float(g0) == scipy.constants.g
    assert float(d) == 1000 * jb["diameter_m"] and float(cd) == DRAG_COEFFICIENT["sphere"]
    tilt7, pull7, tilt4 = quoted(
        page,
        r"tilted from gravity's by ([\d.]+)° in one session \(a steady sideways pull of ([\d.]+) "
        r"m/s²\) and ([\d.]+)° in the other",
    )
    close(tilt7, s7["second_tilt_deg"], 1)
    close(pull7, s7["second_sideways_mps2"], 2)
    close(tilt4, s4["second_tilt_deg"], 2)
    g7, g4, p7, p4, kc, rms, dropped = quoted(
        page,
        r"apparent gravity ([\d.]+) g and ([\d.]+) g, a sideways pull of ([\d.]+) m/s² and "
        r"([\d.]+) m/s² \(in that order\), a drag ([\d.]+) × over all flights, the tracks fitted within ([\d.]+) mm "
        r"RMS, the launcher's push, about (\d+) samples",
    )
    close(g7, s7["cell_g_ratio"], 3)
    close(g4, s4["cell_g_ratio"], 3)
    close(p7, s7["cell_sideways_mps2"], 2)
    close(p4, s4["cell_sideways_mps2"], 2)
    close(kc, jb["cell_drag_ratio"], 2)
    close(rms, 1000 * jb["cell_fit_rms_m"], 1)
    gap = jb["gap"]
    tr = gap["tracks"]
    close(dropped, tr["dropped_samples_mean"], 0)
    bend, early, z, land = quoted(
        page,
        r"bends ([\d.]+) cm off the tracks and comes down ([\d.]+) ms early, z (\d+); the logged "
        r"landings lie (\d+) mm from",
    )
    close(bend, 100 * tr["bend_m"], 1)
    close(early, tr["flight_time_ms"], 1)
    close(z, tr["flight_time_z"], 0)
    close(land, 1000 * tr["landing_m"], 0)
    assert tr["phase"] == "flight" and gap["where"]["phase"] == "flight"
    ga, se = quoted(page, r"\(apparent gravity ([\d.]+) g, standard error ([\d.]+)\)")
    close(ga, tr["g_ratio"], 3)
    close(se, tr["g_ratio_se"], 4)
    assert tr["measurement"] is False
    held, floor, wind = quoted(
        page,
        r"gives `unknown`: held-out ([\d.]+) m against a noise floor of ([\d.]+) m, wind the best "
        r"partial explanation \(([\d.]+) m\)",
    )
    assert gap["verdict"]["effects"] == ["unknown"]
    assert gap["verdict"]["partial_effects"] == ["wind"]
    close(held, gap["baseline"]["heldout_rmse_m"], 3)
    close(floor, gap["noise_floor_m"], 3)
    close(wind, gap["verdict"]["heldout_rmse_m"], 3)


def check_the_real_table_tennis() -> None:
    page, doc = "docs/gap-tracks.md", load_json("docs/figures/real_tracks.json")
    tt = doc["tabletennis"]
    flights, clean, lo, hi, base = quoted(
        page,
        r"MIT; (\d+) flights triangulated .*? the (\d+) clean flights imply (\d+)–(\d+) Hz, so "
        r"(\d+) Hz",
    )
    assert (int(flights), int(clean)) == (tt["flights"], tt["clean_flights"])
    close(lo, tt["implied_rate_hz"][0], 0)
    close(hi, tt["implied_rate_hz"][1], 0)
    assert float(base) == tt["time_base_hz"]
    klo, khi, dmm, mg, cd, rho, knom, share = quoted(
        page,
        r"drag k = ([\d.]+)–([\d.]+) m⁻¹, that of a (\d+) mm, ([\d.]+) g sphere of C_d ([\d.]+) "
        r"in air of ([\d.]+) kg/m³ \(([\d.]+) m⁻¹\), ([\d.]+) of gravity at launch",
    )
    close(klo, tt["second_k_per_m"][0], 2)
    close(khi, tt["second_k_per_m"][1], 2)
    assert (float(dmm), float(mg)) == (1000 * tt["diameter_m"], 1000 * tt["mass_kg"])
    assert (float(cd), float(rho)) == (tt["drag_coefficient"], tt["air_density_kg_m3"])
    close(knom, tt["k_nominal_per_m"], 3)
    close(share, tt["drag_over_gravity_at_launch"], 2)
    dev, kcell, kind, n10 = quoted(
        page,
        r"the same gravity within ([\d.]+) g flight by flight and a median drag ratio of "
        r"([\d.]+) against the second fit's ([\d.]+);.*?With (\d+) throws",
    )
    assert tt["cell_g_ratio_max_dev"] <= float(dev)
    close(dev, tt["cell_g_ratio_max_dev"], 3)
    close(kcell, tt["cell_drag_ratio_median"], 2)
    close(kind, tt["second_drag_ratio_median"], 2)
    assert int(n10) == tt["flights"] and tt["unusable"] == 0


def check_the_real_launcher_flights() -> None:
    page, doc = "docs/gap-tracks.md", load_json("docs/figures/real_tracks.json")
    tc = doc["tennicam"]
    n, hz, jit, gaps = quoted(
        page,
        r"BSD-3-Clause; (\d+) flights of one ball, tracked at (\d+) Hz with the tracker's own "
        r"time stamps, jittered by ([\d.]+) ms, and (\d+) gaps of missing frames",
    )
    assert int(n) == tc["flights"] == tc["episodes"]
    close(hz, 1 / tc["frame_period_s"], 0)
    close(jit, 1000 * tc["stamp_jitter_s"], 1)
    assert int(gaps) == tc["missing_frame_gaps"]
    skip, dmm, mg, cd, kr, knom, speed, g, glo, ghi = quoted(
        page,
        r"from ([\d.]+) s after the ball is first seen to its bounce\) finds the drag of a (\d+) "
        r"mm, ([\d.]+) g sphere of C_d ([\d.]+) \(([\d.]+) × ([\d.]+) m⁻¹\), a launch at "
        r"([\d.]+) m/s, and the ball coming down at ([\d.]+) g \(([\d.]+)–([\d.]+) g flight",
    )
    close(skip, tc["second_skip_frames"] * tc["frame_period_s"], 1)
    assert (float(dmm), float(mg)) == (1000 * tc["diameter_m"], 1000 * tc["mass_kg"])
    from cell.model.objects import DRAG_COEFFICIENT

    assert float(cd) == DRAG_COEFFICIENT["sphere"]
    close(kr, tc["second_drag_ratio_median"], 2)
    close(knom, tc["k_nominal_per_m"], 3)
    close(speed, tc["second_speed_mps_median"], 1)
    close(g, tc["second_g_ratio_median"], 3)
    close(glo, tc["second_g_ratio"][0], 3)
    close(ghi, tc["second_g_ratio"][1], 3)
    gc, kc, rms, dropped = quoted(
        page,
        r"apparent gravity ([\d.]+) g, a drag ([\d.]+) ×, the tracks fitted within ([\d.]+) mm "
        r"RMS, the first (\d+) samples dropped",
    )
    close(gc, tc["cell_g_ratio"], 3)
    close(kc, tc["cell_drag_ratio"], 2)
    close(rms, 1000 * tc["cell_fit_rms_m"], 1)
    close(dropped, tc["cell_dropped_median"], 0)
    assert tc["unusable"] == 0
    gap = tc["gap"]
    tr = gap["tracks"]
    assert tr["g_ratio_objects"] == 1 and tr["g_ratio_off"] and tr["measurement"]
    assert gap["where"]["phase"] == "measurement"
    assert (
        "one object: a tracker's scale and the object's own lift look alike"
        in (gap["where"]["evidence"])
    )
    bend, early, z = quoted(
        page, r"the tracks bend ([\d.]+) cm off the nominal flight and come down ([\d.]+) ms "
        r"early, z (\d+)\)",
    )  # fmt: skip
    close(bend, 100 * tr["bend_m"], 1)
    close(early, -tr["flight_time_ms"], 1)
    close(z, -tr["flight_time_z"], 0)
    held, floor, spin = quoted(
        page,
        r"gives `unknown`: held-out ([\d.]+) m against a noise floor of ([\d.]+) m, spin the "
        r"best partial explanation \(([\d.]+) m\)",
    )
    assert gap["verdict"]["effects"] == ["unknown"]
    assert gap["verdict"]["partial_effects"] == ["spin"]
    close(held, gap["baseline"]["heldout_rmse_m"], 3)
    close(floor, gap["noise_floor_m"], 3)
    close(spin, gap["verdict"]["heldout_rmse_m"], 3)
    r1, r2 = quoted(
        page, r"the landings of two flights \(rows (\d+) and (\d+)\) it\s+flags as outliers"
    )
    assert gap["outliers"]["rows"] == [int(r1), int(r2)]


# -- docs/identify_evidence.md ---------------------------------------------------------------
def check_the_identify_evidence() -> None:
    from cell.identify.algorithm import IdentifyOptions
    from cell.synth import NoiseModel

    page, doc = "docs/identify_evidence.md", load_json("docs/figures/identify_far.json")
    noise, opt = NoiseModel(), IdentifyOptions()
    along, across, floor = quoted(
        page,
        r"σ along the throw = ([\d.]+) % of the reach, across = (\d+) %, both with a (\d+) mm floor",
    )
    close(along, 100 * noise.along_rel, 2)
    close(across, 100 * noise.across_rel, 0)
    close(floor, 1000 * noise.floor_m, 0)
    folds, *widths = quoted(
        page,
        r"(\d+)-fold cross-validation over that object's throws from (\d+) \(keep the "
        r"catalogue\), ([\d.]+), ([\d.]+), ([\d.]+) and ([\d.]+);",
    )
    assert int(folds) == opt.cv_folds
    assert tuple(float(w) for w in widths) == tuple(opt.object_priors)
    (ratio,) = quoted(page, r"tighter than the prior \(ratio < (\d+)\)")
    assert float(ratio) == opt.determined_ratio

    lo, hi, objects, fit_pct, held_pct, fresh = quoted(
        page,
        r"each (\d+)–(\d+) % off the defaults.*?noise, (\d+) thesis objects.*?stratified (\d+) %"
        r".*?on the other (\d+) %.*?on (\d+) new throws",
    )
    assert [float(lo) / 100, float(hi) / 100] == doc["offset_range"]
    cases = doc["cases"]
    assert {c["objects"] for c in cases} == {int(objects)}
    close(fit_pct, 100 * (1 - doc["heldout_fraction"]), 0)
    close(held_pct, 100 * doc["heldout_fraction"], 0)
    (fresh_head,) = quoted(page, r"\| held-out / floor \| fresh (\d+) / floor \|")
    assert int(fresh) == int(fresh_head) == doc["fresh_throws"]
    three = r"([\d.]+), ([\d.]+), ([\d.]+)"
    rows = every(
        page,
        rf"\n\| (\d+) \| (seeds|unseen) (\d+), (\d+), (\d+) \| {three} \| {three} \| {three} \|",
    )
    seen = []
    for n, world, *seeds_and_values in rows:
        seeds, values = seeds_and_values[:3], seeds_and_values[3:]
        for i, seed in enumerate(seeds):
            (c,) = [
                c
                for c in cases
                if (c["n"], c["seed"], c["unseen"]) == (int(n), int(seed), world == "unseen")
            ]
            seen.append(id(c))
            for col, key in enumerate(
                ("heldout_over_floor", "fresh3000_over_floor", "train_over_true")
            ):
                close(values[3 * col + i], c[key], 3)
    assert sorted(seen) == sorted(id(c) for c in cases)  # every case is on the page, once


# -- docs/cli_inputs.md ----------------------------------------------------------------------
def check_the_cli_limits() -> None:
    import math

    from cell.cli.guard import ABSURD, FLOAT_RANGES
    from cell.infile import MAX_NAME_BYTES, MAX_PATH_BYTES
    from cell.log.csvio import MAX_CSV_BYTES
    from cell.log.store import MAX_STORE_BYTES
    from cell.residual.model import MAX_MODEL_BYTES
    from cell.yamlsafe import MAX_BYTES

    page = "docs/cli_inputs.md"
    yaml_mb, csv_mib, model_mib, store_gib = quoted(
        page,
        r"Dynamixel configuration at (\d+) MB .*? a throw or track log at (\d+) MiB, a residual "
        r"model at (\d+) MiB, a throw store at (\d+) GiB\.",
    )
    assert int(yaml_mb) * 10**6 == MAX_BYTES
    assert int(csv_mib) * 2**20 == MAX_CSV_BYTES
    assert int(model_mib) * 2**20 == MAX_MODEL_BYTES
    assert int(store_gib) * 2**30 == MAX_STORE_BYTES
    m_lo, m_hi, s_lo, s_hi, pos, vel, deg, tau, absurd = quoted(
        page,
        r"mass (\d+) to (\d+) kg, extents (\d+) to (\d+) m, positions and targets ±(\d+) m, base "
        r"velocity ±(\d+) m/s, elevation ±π/2 rad \(±(\d+)°\), azimuth and roll ±(\d+)π rad; any "
        r"other number beyond ±(\d+)e6",
    )
    assert (float(m_lo), float(m_hi)) == FLOAT_RANGES["mass"][:2]
    assert (float(s_lo), float(s_hi)) == FLOAT_RANGES["size"][:2]
    for dest in ("at", "target", "current", "box", "land_z"):
        assert FLOAT_RANGES[dest][:2] == (-float(pos), float(pos)), dest
    assert FLOAT_RANGES["base_velocity"][:2] == (-float(vel), float(vel))
    assert FLOAT_RANGES["elevation"][:2] == (-math.pi / 2, math.pi / 2)
    assert math.degrees(FLOAT_RANGES["elevation"][1]) == float(deg)
    for dest in ("azimuth", "roll"):
        assert FLOAT_RANGES[dest][:2] == (-int(tau) * math.pi, int(tau) * math.pi), dest
    assert float(absurd) * 1e6 == ABSURD
    path, name = quoted(
        page, r"A path longer than (\d+) bytes, or with a name longer than (\d+) bytes"
    )
    assert (int(path), int(name)) == (MAX_PATH_BYTES, MAX_NAME_BYTES)


# -- docs/gap_laws.md ------------------------------------------------------------------------
def check_the_gap_laws() -> None:
    import math

    from cell.gap.check_other import OTHER_CASES
    from cell.gap.laws import TERM_PENALTY
    from cell.gap.outliers import OUTLIER_P
    from cell.gap.propose import TERM_PENALTY as PROPOSAL_PENALTY
    from cell.gap.select import MIN_CUT
    from cell.gap.wind_throw import LOGLIK_PENALTY, REPEAT_LR

    page, doc = "docs/gap_laws.md", load_json("docs/figures/gap_check_other.json")
    (pen,) = quoted(page, r"raised by (\d+) % per extra term")
    close(pen, 100 * TERM_PENALTY, 0)
    (cut,) = quoted(page, r"no\s+longer cuts (\d+) % of what the others leave")
    close(cut, 100 * MIN_CUT, 0)
    two, p, sigma, n = quoted(
        page, r"c² = (\d) ln\(n / ([\d.]+)\), about ([\d.]+) σ for (\d+) throws"
    )
    assert (int(two), float(p)) == (2, OUTLIER_P)
    close(sigma, math.sqrt(2 * math.log(int(n) / OUTLIER_P)), 1)
    (ll_pen,) = quoted(page, r"`LOGLIK_PENALTY` = `2 ln\(1 \+ TERM_PENALTY\)` = ([\d.]+) nats")
    close(ll_pen, LOGLIK_PENALTY, 3)
    assert abs(LOGLIK_PENALTY - 2 * math.log(1 + TERM_PENALTY)) < 1e-12
    lr, point, level = quoted(
        page,
        r"`REPEAT_LR` = ([\d.]+), the (\d+) % point of χ² with one degree of\s+freedom: "
        r"a (\d+) % test",
    )
    close(lr, REPEAT_LR, 2)
    close(lr, scipy.stats.chi2.ppf(int(point) / 100, 1), 2)
    assert 100 - int(point) == 2 * int(level)
    (pen,) = quoted(page, r"held-out folds with a (\d+) % penalty per term")
    close(pen, 100 * PROPOSAL_PENALTY, 0)
    (share,) = quoted(page, r"varying throw to throw; (\d+) % outliers")
    shares = {o["outliers"] for *_, o in OTHER_CASES.values() if "outliers" in o}
    assert shares == {int(share) / 100}
    crit = doc["criteria"]
    total, tol, scale, ratio = quoted(
        page,
        r"judges each of its (\d+) cases on: .*? parameters within (\d+) % \(a tracking scale "
        r"within ([\d.]+)\), and the robust held-out RMSE\s+within ([\d.]+) ×",
    )
    assert int(total) == doc["total"] == len(OTHER_CASES)
    close(tol, 100 * crit["param_tol"], 0)
    assert (float(scale), float(ratio)) == (crit["scale_tol"], crit["floor_ratio"])
    passes, total, diag, phase, tol, params, ratio, floor = quoted(
        page,
        r"(\d+) of (\d+) cases pass;\s+verdict right (\d+), phase right (\d+), parameters within "
        r"(\d+) % (\d+), robust held-out RMSE within\s+([\d.]+) × the world's floor (\d+)\.",
    )
    assert (int(passes), int(total)) == (doc["passes"], doc["total"])
    assert (int(diag), int(phase), int(params), int(floor)) == (
        doc["diagonal"],
        doc["phase_ok"],
        doc["params_ok"],
        doc["floor_ok"],
    )
    close(tol, 100 * crit["param_tol"], 0)
    assert float(ratio) == crit["floor_ratio"]
    (drag,) = [c for c in doc["campaigns"] if c["case"] == "o:drag-throw"]
    pt = drag["parameter_throw_to_throw"]
    assert drag["passes"] and drag["verdict"] == "drag_scale" and pt["names"]
    assert drag["laws"]["drag_scale"] == "factor_i ~ N(mean, sd)"
    tool, best, world = quoted(
        page,
        r"repeated throws, ([\d.]+) m, is below what the best constant factor leaves, ([\d.]+) m "
        r"\(the world's own floor ([\d.]+) m\)",
    )
    sd_w, mean_w = quoted(page, r"\(`o:drag-throw`, sd ([\d.]+)\s+about ([\d.]+)\)")
    (world_eff,) = OTHER_CASES["o:drag-throw"][0]
    assert (float(sd_w), float(mean_w)) == (world_eff["sd"], world_eff["value"])
    close(tool, drag["tool_floor_m"], 3)
    close(best, drag["after_m"], 3)
    close(world, drag["world_floor_m"], 3)
    mean, sd, lo, hi, fs, a_d = quoted(
        page,
        r"the mean\s+([\d.]+) and the sd ([\d.]+) \(interval ([\d.]+)–([\d.]+)\), the floor its "
        r"spread sets ([\d.]+) m, A ([\d.]+)\s+× the world's floor",
    )
    close(mean, drag["params"]["drag_scale"]["factor"], 3)
    close(sd, drag["params"]["drag_scale"]["sd"], 3)
    close(lo, pt["sd_ci95"][0], 3)
    close(hi, pt["sd_ci95"][1], 3)
    close(fs, pt["floor_m"], 4)
    close(a_d, drag["after_over_floor"], 2)
    varying = [
        c
        for c in doc["campaigns"]
        if c["case"].endswith("-throw") and c["case"] not in ("o:wind-throw", "o:drag-throw")
    ]
    assert [c["case"] for c in varying] == ["o:bm-throw", "o:pitch-throw"]
    worlds = {c["case"]: OTHER_CASES[c["case"]][0][0] for c in varying}
    for c in varying:  # named by its one value, read as drawn throw to throw: no row flagged
        pt = c["parameter_throw_to_throw"]
        assert c["passes"] and c["outlier_rows"] == [] and pt["tried_for"] == "outliers"
        assert c["laws"][pt["effect"]] == f"{pt['param']}_i ~ N(mean, sd)"
    got = quoted(
        page,
        r"the mean ([\d.]+) kg and the sd ([\d.]+) \(interval\s+([\d.]+)–([\d.]+)\) for the "
        r"world's ([\d.]+) and ([\d.]+); the pitch as the mean ([\d.]+) rad and the\s+sd ([\d.]+) "
        r"\(interval ([\d.]+)–([\d.]+)\) for ([\d.]+) and ([\d.]+); A ([\d.]+) and ([\d.]+) × ",
    )
    for k, c in enumerate(varying):
        pt, world = c["parameter_throw_to_throw"], worlds[c["case"]]
        mean, sd, lo, hi, w_mean, w_sd = got[6 * k : 6 * k + 6]
        close(mean, pt["mean"], 4)
        close(sd, pt["sd"], 4)
        close(lo, pt["sd_ci95"][0], 4)
        close(hi, pt["sd_ci95"][1], 4)
        assert (float(w_mean), float(w_sd)) == (world["value"], world["sd"])
        assert c["world_floor_kept_m"] == c["world_floor_m"]  # on every row
        close(got[12 + k], c["after_over_floor"], 2)
    moved = [c for c in doc["campaigns"] if c["outliers_true"]]
    assert moved and all(
        c["outliers_found"] == c["outliers_true"] and c["outliers_false"] == 0 for c in moved
    )
    (a_f,) = quoted(page, r"no\s+row flagged in `o:wind-throw`, and A ([\d.]+) × the world's floor")
    (wt,) = [c for c in doc["campaigns"] if c["case"] == "o:wind-throw"]
    assert (
        wt["passes"] and wt["outliers_false"] == 0 and wt["laws"]["wind"] == "wind_i ~ N(mean, sd)"
    )
    close(a_f, wt["after_over_floor"], 2)
    n_cli, workers = quoted(page, r"`cell gap check --worlds other --n (\d+) --workers (\d)")
    assert int(n_cli) > 0 and int(workers) >= 1
