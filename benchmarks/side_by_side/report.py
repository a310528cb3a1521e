"""The run's table: side_by_side.txt (and stdout) from the results that go
into side_by_side.json, and the flat list of every ratio."""

from __future__ import annotations


def all_ratios(res: dict) -> dict:
    out = {}
    for k, v in res.get("vdb_write", {}).get("ratios", {}).items():
        out[f"vdb_write.{k}"] = v
    for k, v in res.get("gather", {}).get("ratios", {}).items():
        out[f"gather.{k}"] = v
    for case, c in res["render"]["cases"].items():
        for k, v in c["ratios"].items():
            out[f"render.{case}.{k}"] = v
    return out


def fmt_s(x: float) -> str:
    return f"{x:.3f}" if x < 10 else f"{x:.1f}"


def report_vdb_gather(res: dict, L: list) -> None:
    v = res["vdb_write"]
    i = v["input"]
    L.append(f"1. VDB writer: the default bake's grids ({', '.join(i['grids'])}: {i['active_voxels']:,} active voxels, "
             f"{i['leaves']:,} leaves, f32), best of {v['repeats']} runs, writers alternating")
    L.append(f"   {'writer':<34} {'compression':<22} {'class':<11} {'best s':>8} {'bytes':>13}")
    names = {"aurora_zip": "aurora (Rust)", "cpp_zip": "OpenVDB C++", "aurora_blosc": "aurora (Rust)",
             "pyopenvdb_blosc": "pyopenvdb.write", "cpp_blosc": "OpenVDB C++"}
    for k in ("aurora_zip", "cpp_zip", "aurora_blosc", "pyopenvdb_blosc", "cpp_blosc"):
        f = v["files"][k]
        gm = next(iter(f["grids"].values()))
        cls = sorted({x["class"] for x in f["grids"].values()})
        L.append(f"   {names[k]:<34} {str(gm['file_compression']):<22} {'/'.join(cls):<11} "
                 f"{v['best_s'][k]:>8.3f} {f['bytes']:>13,}")
    r = v["ratios"]
    L.append(f"   ours / OpenVDB C++, ZIP + active mask (like for like): time {r['ours_over_cpp_zip_time']:.3f}, "
             f"size {r['ours_over_cpp_zip_bytes']:.4f}")
    L.append(f"   ours (ZIP) / pyopenvdb (Blosc, its only choice; not like for like): time "
             f"{r['ours_zip_over_pyopenvdb_blosc_time']:.3f}, size {r['ours_zip_over_pyopenvdb_blosc_bytes']:.4f}")
    L.append(f"   pyopenvdb / OpenVDB C++, both Blosc + active mask: time {r['pyopenvdb_over_cpp_blosc_time']:.3f}")
    L.append(f"   ours Blosc / ours ZIP: time {r['ours_blosc_over_ours_zip_time']:.3f}; ours / OpenVDB C++, both Blosc + "
             f"active mask: time {r['ours_blosc_over_cpp_blosc_time']:.3f}, size {r['ours_blosc_over_cpp_blosc_bytes']:.4f}")
    rb = v["read_back"]
    L.append(f"   read back with pyopenvdb: ours == pyopenvdb's file, == C++ ZIP file, == C++ Blosc file: "
             f"{rb['ours_vs_pyopenvdb']['equal'] and rb['ours_vs_cpp_zip']['equal'] and rb['ours_vs_cpp_blosc']['equal']}, "
             f"our Blosc file == the bake: {rb['ours_blosc']['equal']} "
             f"(every active voxel, exact values)")
    L.append(f"   (in the bake itself our writer took {i['bake_vdb_write_s']:.2f} s, one run)")
    L.append("")

    gth = res["gather"]
    L.append(f"2. Gather (default scene{' reduced' if res['mode'] == 'quick' else ''}, "
             f"{gth['methods']['kdtree']['photons']:,} photons, {gth['methods']['kdtree']['active_voxels']:,} voxels), "
             f"times_s.gather best of {gth['repeats']}")
    for k, mm in gth["methods"].items():
        L.append(f"   {k:<11} {mm['best_gather_s']:>8.2f} s   (runs {', '.join(f'{x:.2f}' for x in mm['gather_s'])})")
    L.append(f"   splat / kdtree {gth['ratios']['splat_over_kdtree_time']:.3f}; report2014 / kdtree "
             f"{gth['ratios']['report2014_over_kdtree_time']:.3f}")
    L.append(f"   note: {gth['note']}")
    L.append("")


def report_render(res: dict, L: list) -> None:
    rr = res["render"]
    # The dome case has its own size, printed on its own line.
    size = f"{rr['size'][0]}x{rr['size'][1]}, " if any(c != "dome" for c in rr["cases"]) else ""
    L.append(f"3. aurora render against Cycles at equal error ({size}{rr['threads']} threads "
             f"each, pixel-area sampling in both)")
    for case, c in rr["cases"].items():
        ref = c["reference"]
        if case == "dome":
            b = c["bake"]
            L.append(f"   dome: the {b['preset']} preset's dome master at {c['size'][0]}x{c['size'][1]} (180-degree "
                     f"equidistant fisheye looking up), baked for it{' with ' + str(b['edits']) if b['edits'] else ''} "
                     f"in {b['wall_s']:.1f} s; errors inside the image circle")
        L.append(f"   {case}: reference = aurora render, {ref['samples_per_pixel_total']} samples/pixel "
                 f"({ref['subpixels'] + ' sub-pixels x ' if ref['subpixels'] != '1' else ''}{ref['spp_per_seed']} spp x 2 seeds"
                 f"{', %d shadow samples per terrain hit' % ref['shadow_samples'] if case == 'terrain' else ''}); its own error ~{100 * ref['own_error_estimate']:.2f}%")
        st = c.get("stat", "best")
        L.append(f"     {'renderer':<8} {'samples':>7} {'error %':>8} {'flux':>8} {st + ' wall s':>13} {st + ' cpu s':>12} runs")
        names = {"aurora": "aurora", "aurora_adaptive": "aurora+ad", "cycles": "cycles", "cycles_adaptive": "cycles+ad"}
        for who in c["ladders"]:
            for e in c["ladders"][who]:
                L.append(f"     {names[who]:<9} {e['samples']:>6} {100 * e['error']:>8.3f} {e['flux_ratio']:>8.4f} "
                         f"{fmt_s(e[st + '_wall_s']):>13} {fmt_s(e[st + '_cpu_s']):>12} {len(e['runs']):>4}")
        if "aurora_adaptive" in c["ladders"]:
            L.append("     aurora+ad: aurora render --adaptive (a uniform first pass, the rest of the samples "
                     "shared by the pixels' relative spread; samples = the mean per pixel)")
        if c.get("cycles_adaptive_threshold") is not None:
            L.append(f"     cycles+ad: Cycles with adaptive sampling on (noise threshold {c['cycles_adaptive_threshold']}, "
                     "automatic minimum samples; samples = the maximum per pixel)")
        # The dome's figure is the comparison at aurora's lowest rung (below).
        for tt in [] if case == "dome" else c.get("targets") or [{"target_error": c["target_error"],
                                                                  "equal_error": c["equal_error"],
                                                                  "ratios": c["ratios"]}]:
            eqs, rt = tt["equal_error"], tt["ratios"]
            ea = eqs["aurora"]
            L.append(f"     at {100 * tt['target_error']:.1f}% error: aurora {ea['samples']:.0f} spp, {ea['wall_s']:.2f} s "
                     f"({ea['how']})")
            for who in [w for w in ("cycles", "cycles_adaptive") if w in eqs]:
                ec = eqs[who]
                suffix = "_adaptive" if who == "cycles_adaptive" else ""
                L.append(f"       {names[who]:<9} {ec['samples']:.0f} samples, {ec['wall_s']:.2f} s ({ec['how']}); "
                         f"aurora / Cycles wall {rt['aurora_over_cycles' + suffix + '_wall']:.3f}, cpu "
                         f"{rt['aurora_over_cycles' + suffix + '_cpu']:.3f} (Cycles / aurora "
                         f"{1 / rt['aurora_over_cycles' + suffix + '_wall']:.1f}x wall, "
                         f"{1 / rt['aurora_over_cycles' + suffix + '_cpu']:.1f}x cpu)")
            if "aurora_adaptive" in eqs:
                ead = eqs["aurora_adaptive"]
                L.append(f"       aurora+ad {ead['samples']:.0f} spp, {ead['wall_s']:.2f} s ({ead['how']})")
                for who in [w for w in ("cycles", "cycles_adaptive") if w in eqs]:
                    k = "aurora_adaptive_over_" + who
                    L.append(f"         against {names[who]:<9}: wall {rt[k + '_wall']:.3f}, cpu {rt[k + '_cpu']:.3f} "
                             f"(Cycles / aurora+ad {1 / rt[k + '_wall']:.1f}x wall, {1 / rt[k + '_cpu']:.1f}x cpu)")
        lo = c.get("at_aurora_lowest_rung")
        if lo:
            la, lc = lo["aurora"], lo["cycles"]
            rel = "" if lo["relation"] == "=" else lo["relation"] + " "
            L.append(f"     at aurora's lowest rung ({la['samples']} spp, {100 * la['error']:.3f}% error, "
                     f"{la['wall_s']:.2f} s wall, {la['cpu_s']:.2f} s cpu): Cycles {lc['samples']:.0f} samples"
                     + (f" ({100 * lc['error']:.3f}% error)" if "error" in lc else "")
                     + f", {lc['wall_s']:.1f} s wall, {lc['cpu_s']:.1f} s cpu ({lc['how']})")
            L.append(f"       Cycles / aurora {rel}{lc['wall_s'] / la['wall_s']:.1f}x wall, "
                     f"{rel}{lc['cpu_s'] / la['cpu_s']:.1f}x cpu")
        cc = c["cycles_converged"]
        L.append(f"     Cycles at {cc['samples']} samples: {100 * cc['error']:.2f}% from the reference, flux "
                 f"{cc['flux_ratio']:.4f} (cross-check bias {100 * cc['known_cross_check_bias']:.2f}%): "
                 f"{'agrees' if cc['agrees'] else 'DISAGREES'}")
    L.append(f"   Cycles times exclude Blender's start-up, the add-on's scene set-up and the one-off VDB padding "
             f"({rr['cycles_padding_s']:.1f} s)")
    L.append("")


def report_text(res: dict) -> str:
    m, L = res["machine"], []
    L.append(f"aurora side by side ({res['mode']} run), {res['started_utc']} -> {res['finished_utc']} UTC, "
             f"{res['wall_s']:.0f} s")
    L.append(f"machine: {m['cpu_model']}, nproc {m['nproc']}, MemTotal {m['mem_total_kb'] / 1048576:.1f} GiB, "
             f"load average {' '.join(map(str, res['load_start']))} at start, {' '.join(map(str, res['load_end']))} at end (shared with other jobs)")
    g = res["git"]
    L.append(f"git {g['commit'][:12]}{' (uncommitted changes)' if g['dirty'] else ''}; {res['aurora_version']}; "
             f"OpenVDB {res['openvdb_version']}; Blender {res['render']['blender']}")
    L.append("ratios are ours / theirs: below 1, aurora is faster (or its file smaller)")
    L.append("")

    if "vdb_write" not in res:
        L.append("1. VDB writer: skipped (--render-only)")
        L.append("2. Gather: skipped (--render-only)")
        L.append("")
    else:
        report_vdb_gather(res, L)
    report_render(res, L)
    s = res["seed2014"]
    if s.get("skipped"):
        L.append(f"4. seed2014: skipped ({s['why']})")
    else:
        st = ", ".join(f"{k} {v:.1f} s" for k, v in sorted(s["stages_s"].items(), key=lambda kv: -kv[1]))
        L.append(f"4. seed2014 ({s['beams']:,} beams, {s['photons']:,} photons, {s['active_voxels']:,} active voxels, "
                 f"{s['voxel_size_km']} km voxels): wall {s['wall_s']:.0f} s, peak RSS {s['peak_rss_kb'] / 1048576:.2f} GiB, "
                 f"CPU {s['cpu_s']:.0f} s")
        L.append(f"   stages: {st}; VDB write {s['vdb_write_s']:.1f} s ({s['vdb_bytes']:,} bytes)")
        L.append(f"   dominant: {s['dominant_stage']} ({100 * s['dominant_share_of_wall']:.0f}% of the wall time)")
    L.append("")
    L.append("all ratios:")
    for k, x in res["ratios"].items():
        L.append(f"   {k:<55} {x:.4f}")
    return "\n".join(L) + "\n"
