"""Manifest and dataset card, rebuilt from the sample folders after every run."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from bittc_core.atomic import write_text_atomic
from bittc_core.data.format import FORMAT_VERSION, SPLITS, TAU_BIN_EDGES_S, tau_bin_labels

CARD = "dataset_card.json"
MANIFEST = "manifest.jsonl"


def scan(out: Path) -> list[dict]:
    """Every complete sample (folders named by index) with its meta, split by split."""
    rows = []
    for split in SPLITS:
        d = out / split
        if not d.is_dir():
            continue
        for sd in sorted(p for p in d.iterdir() if p.is_dir() and p.name.isdigit()):
            try:
                meta = json.loads((sd / "meta.json").read_text())
            except (OSError, ValueError):
                continue
            rows.append(
                {
                    "split": split,
                    "index": int(sd.name),
                    "seed": meta["seed"],
                    "path": f"{split}/{sd.name}",
                    "n_frames": meta["n_frames"],
                    "n_actors": len(meta["actors"]),
                    "_hist": meta["tau_histogram_actor_px"],
                }
            )
    return rows


def summarize(rows: list[dict]) -> dict:
    splits: dict[str, dict] = {}
    total_hist: dict[str, int] = dict.fromkeys(tau_bin_labels(), 0)
    for r in rows:
        s = splits.setdefault(
            r["split"],
            {
                "samples": 0,
                "seed_min": r["seed"],
                "seed_max": r["seed"],
                "actors": 0,
                "tau_histogram_actor_px": dict.fromkeys(tau_bin_labels(), 0),
            },
        )
        s["samples"] += 1
        s["seed_min"], s["seed_max"] = min(s["seed_min"], r["seed"]), max(s["seed_max"], r["seed"])
        s["actors"] += r["n_actors"]
        for k, v in r["_hist"].items():
            s["tau_histogram_actor_px"][k] += v
            total_hist[k] += v
    n = sum(total_hist.values())
    if n == 0:
        return {
            "splits": splits,
            "tau_histogram_actor_px": total_hist,
            "tau_share_actor_px": None,
            "largest_bin_share": None,
        }
    share = {k: round(v / n, 4) for k, v in total_hist.items()}
    return {
        "splits": splits,
        "tau_histogram_actor_px": total_hist,
        "tau_share_actor_px": share,
        "largest_bin_share": max(share.values()),
    }


def rebuild_manifest_and_card(out: Path, cfg) -> dict:
    """Rewrite the manifest and the card from the samples on disk. Both depend on the samples
    only, never on how they were made (worker count, backend, timings, resumed runs)."""
    rows = scan(out)
    write_text_atomic(
        out / MANIFEST, "".join(json.dumps({k: v for k, v in r.items() if not k.startswith("_")}) + "\n" for r in rows)
    )
    card = {
        "format_version": FORMAT_VERSION,
        "generation": asdict(cfg),
        "tau_bin_edges_s": list(TAU_BIN_EDGES_S),
        **summarize(rows),
        "notes": "tau from the latest frame's capture time; histogram over actor pixels (instance > 0) of the "
        "latest pair.",
    }
    write_text_atomic(out / CARD, json.dumps(card, indent=2) + "\n")
    return card
