"""tools/render_pages.py: pages rendered in headless Chromium, tile by tile, with the
console's messages."""

import importlib.util
import shutil
from pathlib import Path

import pytest
from PIL import Image

TOOL = Path(__file__).resolve().parents[1] / "tools" / "render_pages.py"
spec = importlib.util.spec_from_file_location("render_pages", TOOL)
render_pages = importlib.util.module_from_spec(spec)
spec.loader.exec_module(render_pages)

PAGE = """<!DOCTYPE html><html><head><meta charset="utf-8"></head><body style="margin:0">
<div style="height:300px;background:#ff0000"></div><div style="height:300px;background:#0000ff">
</div><script>console.error("broken figure")</script></body></html>"""


def test_a_tile_is_the_page_shifted_up_by_its_offset():
    shifted = render_pages.shifted_page(PAGE, 300)
    assert '<head><style>body{position:relative;top:-300px}</style><meta' in shifted
    assert render_pages.shifted_page("<p>x</p>", 10).startswith("<style>")


def test_chromium_is_asked_for_a_screenshot_at_the_device_pixel_ratio_of_1(tmp_path):
    command = render_pages.chromium_command("chromium", tmp_path / "p.html",
                                            tmp_path / "p.png", 1280, 2000)
    assert "--force-device-scale-factor=1" in command and "--window-size=1280,2000" in command
    assert command[-1] == (tmp_path / "p.html").as_uri()


@pytest.mark.skipif(shutil.which("chromium") is None,
                    reason="needs Debian's chromium (apt-get install chromium)")
def test_a_page_renders_tile_by_tile_until_it_ends_and_its_console_is_reported(tmp_path):
    page = tmp_path / "page.html"
    page.write_text(PAGE)
    pngs, console = render_pages.render(page, tmp_path / "out", shutil.which("chromium"),
                                        width=200, tile=300)
    assert [p.name for p in pngs] == ["page_0.png", "page_1.png"]       # the third is blank
    colours = [Image.open(p).convert("RGB").getpixel((100, 150)) for p in pngs]
    assert colours == [(255, 0, 0), (0, 0, 255)]
    assert Image.open(pngs[0]).size == (200, 300)
    assert any("broken figure" in message for message in console)
    assert not list(tmp_path.glob(".*.render.html"))                    # cleaned up
