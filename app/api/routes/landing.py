"""GET /: the landing page (static/index.html with links, presets and figures filled in).

index.html holds markers that this route replaces: ``<!--scene-link-->`` (the scene URL from
the settings), ``{{API}}`` (this server's base URL, so the curl examples can be copied),
``<!--presets-->`` (one card per preset, with its screenshot ``static/img/NAME.png`` when it
exists) and ``<!--bench-->`` (the PNGs in ``static/img/bench/`` and in the settings' ``bench_dir``,
``bench/figures`` of the repository, served at ``/bench/figures``).
"""

from __future__ import annotations

import html
from pathlib import Path

from fastapi import APIRouter, HTTPException, Request
from fastapi.responses import HTMLResponse

from ..deps import SettingsDep
from ..presets_source import preset_summaries

router = APIRouter(include_in_schema=False)


def _scene_link(scene_url: str | None) -> str:
    if scene_url:
        url = html.escape(scene_url, quote=True)
        lesson = html.escape(scene_url.rstrip("/") + "/?lesson=paper&step=1", quote=True)  # app.scene.common.lesson
        return (f'<p><a id="scene-link" class="button" href="{url}">Open the 3D scene</a> '
                f'<a id="lesson-link" class="button" href="{lesson}">A lesson: the paper, step by step</a></p>')
    return '<p id="scene-link" class="muted">The 3D scene is not running on this server (API only).</p>'


def scene_link(scene_url: str, preset: str) -> str:
    """The scene's link that opens a new tab on ``preset`` (``/c/<configuration>/``).

    Examples:
        >>> scene_link("http://127.0.0.1:8080", "example-29").startswith("http://127.0.0.1:8080/c/")
        True
    """
    from app.scene.common.links import link_path

    return scene_url.rstrip("/") + link_path({"preset": preset})


def _presets(static_dir: Path, scene_url: str | None) -> str:
    cards = []
    for name, description in preset_summaries():
        esc = html.escape(name)
        # the card opens the preset in the scene (its picture too), when the scene runs
        target = html.escape(scene_link(scene_url, name), quote=True) if scene_url else f"/static/img/{esc}.png"
        img = ""
        if (static_dir / "img" / f"{name}.png").is_file():
            img = f'<a href="{target}"><img src="/static/img/{esc}.png" alt="{esc}" loading="lazy"></a>'
        opener = f' <a class="open-scene" href="{target}">Open in the scene</a>' if scene_url else ""
        cards.append(
            f'<figure class="preset" id="preset-{esc}">{img}<figcaption><b>{esc}</b>: '
            f'{html.escape(description)}{opener} <a href="/api/presets/{esc}">JSON</a></figcaption></figure>'
        )
    if not cards:
        return '<p class="muted">No presets available on this server.</p>'
    return '<div class="grid">' + "".join(cards) + "</div>"


def _bench(static_dir: Path, bench_dir: Path | None) -> str:
    figures = [(f"/static/img/bench/{p.name}", p.stem) for p in sorted((static_dir / "img" / "bench").glob("*.png"))]
    if bench_dir is not None and bench_dir.is_dir():  # the live report, unless copied to static/
        copied = {stem for _, stem in figures}
        figures += [(f"/bench/figures/{p.name}", p.stem) for p in sorted(bench_dir.glob("*.png")) if p.stem not in copied]
    if not figures:
        return ('<p class="muted">Benchmark figures will appear here once the benchmark report has been '
                "generated (<code>python -m bench.report</code>).</p>")
    return '<div class="grid">' + "".join(
        f'<figure><a href="{html.escape(url)}"><img src="{html.escape(url)}" alt="{html.escape(stem)}"></a>'
        f"<figcaption>{html.escape(stem)}</figcaption></figure>"
        for url, stem in figures
    ) + "</div>"


@router.get("/", response_class=HTMLResponse)
def landing(request: Request, settings: SettingsDep) -> HTMLResponse:
    """The landing page; 404 when no static folder was found."""
    static_dir = settings.static_dir
    if static_dir is None or not (static_dir / "index.html").is_file():
        raise HTTPException(404, "no landing page: static/index.html not found")
    page = (static_dir / "index.html").read_text(encoding="utf-8")
    page = page.replace("<!--scene-link-->", _scene_link(settings.scene_url))
    page = page.replace("{{API}}", html.escape(str(request.base_url).rstrip("/")))
    page = page.replace("<!--presets-->", _presets(static_dir, settings.scene_url))
    page = page.replace("<!--bench-->", _bench(static_dir, settings.bench_dir))
    return HTMLResponse(page)
