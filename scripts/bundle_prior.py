"""Ship a trained prior as the bundled one, keeping the history of the weights it replaces.

Run: .venv/bin/python scripts/bundle_prior.py RUN_OR_MODEL --data "DESCRIPTION" [--dest DIR]
         [--previous-note "TEXT"] [--dry-run]

RUN_OR_MODEL is a training run (its ``best/`` model is taken) or a model folder of either model
family (the panoramic VAE, or VENI / VENI+D, shipped as ``--dest src/roomlight/assets/veni`` and
``.../veni-d``). The weights are
copied byte for byte into DEST (default ``src/roomlight/assets/prior``) and its ``config.json`` is
the new model's, with two additions in ``metadata``:

- ``data``: how the training rooms were made (``--data``), and ``best_step`` from the run;
- ``earlier_schedules``: the list the bundled prior already carried, plus one entry for the
  weights being replaced (their training configuration, checksum, best step, data and a note).

A schedule started with ``--init-from src/roomlight/assets/prior`` names the bundle in its
``init_from``; the entry appended here says which weights that was. Afterwards the new bundle is
loaded back and compared tensor by tensor with the source, and the script refuses to overwrite
the bundle with a model of another architecture or resolution unless ``--allow-new-architecture``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import sys
import tempfile
from pathlib import Path

import torch

from roomlight.errors import RoomlightError
from roomlight.prior.model.families import load_model
from roomlight.prior.model.saved import CONFIG_NAME, WEIGHTS_NAME
from roomlight.prior.model.runs import resolve_run_model
from roomlight.prior.model.weights import file_sha256


def _best_step(model_dir: Path) -> int | None:
    """The step ``roomlight train`` recorded with its best model (``RUN/best/best.json``), if any."""
    record = model_dir / "best.json"
    return int(json.loads(record.read_text())["step"]) if record.exists() else None


def bundled_config(new_cfg: dict, old_cfg: dict | None, data: str, best_step: int | None,
                   previous_note: str) -> dict:
    """The DEST config.json: the new model's, its ``metadata`` extended with the history."""
    cfg = json.loads(json.dumps(new_cfg))  # a deep copy of plain JSON
    meta = dict(cfg.get("metadata") or {})
    history = []
    if old_cfg is not None:
        old_meta = old_cfg.get("metadata") or {}
        history = list(old_meta.get("earlier_schedules") or [])
        entry = {"training": old_cfg.get("training"), "weights_sha256": old_cfg.get("weights_sha256")}
        for key in ("best_step", "data"):
            if key in old_meta:
                entry[key] = old_meta[key]
        entry["note"] = previous_note
        history.append(entry)
    meta["data"] = data
    if best_step is not None:
        meta["best_step"] = best_step
    else:
        meta.pop("best_step", None)
    meta["earlier_schedules"] = history
    cfg["metadata"] = meta
    return cfg


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("source", help="training run (its best/ model) or model folder")
    ap.add_argument("--data", required=True, help="how the training rooms were made, recorded in metadata.data")
    ap.add_argument("--dest", default="src/roomlight/assets/prior")
    ap.add_argument("--previous-note", default="the bundled prior before the schedule that replaced it; "
                    "init_from names that model")
    ap.add_argument("--allow-new-architecture", action="store_true")
    ap.add_argument("--dry-run", action="store_true", help="print the new config.json, change nothing")
    args = ap.parse_args(argv)

    src = Path(resolve_run_model(args.source))
    if not (src / WEIGHTS_NAME).exists() or not (src / CONFIG_NAME).exists():
        sys.exit(f"{src}: not a roomlight model folder ({WEIGHTS_NAME} + {CONFIG_NAME})")
    new_cfg = json.loads((src / CONFIG_NAME).read_text())
    dest = Path(args.dest)
    old_cfg = json.loads((dest / CONFIG_NAME).read_text()) if (dest / CONFIG_NAME).exists() else None
    if old_cfg is not None and (old_cfg.get("model") != new_cfg.get("model")
                                or old_cfg.get("format") != new_cfg.get("format")) and not args.allow_new_architecture:
        sys.exit(f"{src} has another architecture than {dest} (model settings differ); "
                 "pass --allow-new-architecture if that is intended")
    if old_cfg is not None and old_cfg.get("weights_sha256") == file_sha256(src / WEIGHTS_NAME):
        sys.exit(f"{dest} already holds these weights")
    cfg = bundled_config(new_cfg, old_cfg, args.data, _best_step(src), args.previous_note)
    text = json.dumps(cfg, indent=2, default=str) + "\n"
    if args.dry_run:
        print(text)
        return 0

    had_view_encoder = (dest / "view_encoder").is_dir()
    # Write into a sibling temporary folder and swap it in, so an interruption leaves either the
    # old bundle or the new one, never a mix of one's weights and the other's config.
    dest.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=".bundle-", dir=dest.parent))
    tmp.chmod(0o755)  # mkdtemp makes it private; package data must be readable by every user
    shutil.copyfile(src / WEIGHTS_NAME, tmp / WEIGHTS_NAME)
    (tmp / CONFIG_NAME).write_text(text)
    try:  # loading verifies the copy against the recorded weights_sha256
        loaded, reference = load_model(tmp), load_model(src)
    except RoomlightError as e:
        shutil.rmtree(tmp)
        sys.exit(f"the copy does not load: {e}")
    a, b = loaded.state_dict(), reference.state_dict()
    if a.keys() != b.keys() or not all(torch.equal(a[k], b[k]) for k in a):
        shutil.rmtree(tmp)
        sys.exit("the copied weights load differently from the source")
    old = dest.with_name(dest.name + ".replaced")
    if dest.exists():
        if old.exists():
            shutil.rmtree(old)
        dest.rename(old)
    tmp.rename(dest)
    if old.exists():
        shutil.rmtree(old)
    print(f"{dest}: {src} (sha256 {cfg['weights_sha256'][:12]}, best step {cfg['metadata'].get('best_step')}), "
          f"{len(cfg['metadata']['earlier_schedules'])} earlier schedules recorded; {len(a)} tensors identical")
    if had_view_encoder:
        print(f"note: the view encoder of the replaced weights was trained for them and is not carried over; train "
              f"one for these with `roomlight train-view-encoder --model {dest}` and copy its best/ into "
              f"{dest}/view_encoder (until then fit-photo starts from the paper's samples)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
