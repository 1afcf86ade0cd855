"""Render HTML pages in headless Chromium to PNG, as a reader sees them at normal zoom.

    python tools/render_pages.py results/evaluate/evaluation.html results/mc/x/report.html \
        --out results/pages [--width 1280] [--tile 2000]

Each page becomes ``OUT/<page stem>_<k>.png``: tiles of ``--tile`` px of the page, top to
bottom, ``--width`` px wide at a device pixel ratio of 1 (what a 1280 px browser window shows
at 100 %), until a tile is white. Chromium screenshots only its window and ignores a URL's
#fragment, so each tile renders a copy of the page shifted up by the tile's offset (a style
added to the page, written beside it and removed after). The console messages Chromium logs
(a script error, a missing resource) are printed; the exit status is 1 if there were any.

Needs Debian's ``chromium`` (``apt-get install chromium``) or ``--browser PATH``.
"""

import argparse
import re
import shutil
import subprocess
import sys
from pathlib import Path

from PIL import Image

CONSOLE = re.compile(r":CONSOLE[^\]]*\] (.*)")
"""A console message in Chromium's log on stderr."""
TIMEOUT = 120.0
"""Seconds one screenshot may take on a loaded machine."""


def shifted_page(html: str, offset: int) -> str:
    """``html`` with its content moved up by ``offset`` px (the tile at that offset)."""
    style = f"<style>body{{position:relative;top:-{offset}px}}</style>"
    head = re.search(r"<head[^>]*>", html, re.IGNORECASE)
    at = head.end() if head else 0
    return html[:at] + style + html[at:]


def chromium_command(browser: str, page: Path, png: Path, width: int, height: int) -> list[str]:
    """The headless screenshot of ``page`` into ``png``, ``width`` x ``height`` px."""
    return [browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
            "--force-device-scale-factor=1", f"--window-size={width},{height}",
            "--enable-logging=stderr", "--v=0", f"--screenshot={png}",
            page.resolve().as_uri()]


def is_blank(png: Path) -> bool:
    """Whether every pixel of ``png`` is white (the page ended above this tile)."""
    with Image.open(png) as image:
        return image.convert("RGB").getextrema() == ((255, 255), (255, 255), (255, 255))


def render(page: Path, out: Path, browser: str, width: int = 1280, tile: int = 2000,
           max_tiles: int = 40) -> tuple[list[Path], list[str]]:
    """Render ``page`` into tiles in ``out``: (the PNGs, the console messages)."""
    out.mkdir(parents=True, exist_ok=True)
    html = page.read_text(encoding="utf-8")
    pngs: list[Path] = []
    console: list[str] = []
    shifted = page.with_name(f".{page.stem}.render.html")
    try:
        for k in range(max_tiles):
            png = out / f"{page.stem}_{k}.png"
            shifted.write_text(shifted_page(html, k * tile), encoding="utf-8")
            done = subprocess.run(chromium_command(browser, shifted, png, width, tile),
                                  capture_output=True, text=True, timeout=TIMEOUT)
            if not png.is_file():
                raise RuntimeError(f"{browser} wrote no screenshot of {page}: "
                                   f"{done.stderr.strip()[-500:]}")
            if k == 0:
                console = CONSOLE.findall(done.stderr)
            if k and is_blank(png):
                png.unlink()
                break
            pngs.append(png)
    finally:
        shifted.unlink(missing_ok=True)
    return pngs, console


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("pages", nargs="+", type=Path, help="HTML files")
    parser.add_argument("--out", type=Path, default=Path("results/pages"),
                        help="folder of the PNGs (default: results/pages)")
    parser.add_argument("--width", type=int, default=1280, help="window width, px")
    parser.add_argument("--tile", type=int, default=2000, help="tile height, px")
    parser.add_argument("--browser", default="chromium", help="Chromium executable")
    args = parser.parse_args(argv)
    browser = shutil.which(args.browser)
    if browser is None:
        print(f"error: --browser {args.browser}: not found (apt-get install chromium)",
              file=sys.stderr)
        return 2
    missing = [str(p) for p in args.pages if not p.is_file()]
    if missing:
        print(f"error: no such page: {', '.join(missing)}", file=sys.stderr)
        return 2
    status = 0
    for page in args.pages:
        pngs, console = render(page, args.out, browser, args.width, args.tile)
        print(f"{page}: {len(pngs)} tile(s) of {args.width}x{args.tile} px in {args.out}")
        for message in console:
            print(f"  console: {message}")
            status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
