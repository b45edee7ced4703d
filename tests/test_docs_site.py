"""The built documentation site (issue 24, item 1), as a reader gets it: every local link and
anchor resolves, and in headless Chromium every image of every page that has one loads and
decodes. The site is built by `make docs` (warnings are errors), which .ci/run runs before
this module (`pytest -m docs_site`); the default run leaves it out (the build runs the
gallery, about 40 s)."""
import json
import os
import re
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

pytestmark = pytest.mark.docs_site

ROOT = Path(__file__).resolve().parents[1]
SITE = Path(os.environ.get("EMPACT_DOCS_HTML", ROOT / "docs" / "_build" / "html"))
CHROMIUM_FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic",
                  "--no-first-run", "--disable-background-networking",
                  "--disable-component-update", "--disable-sync"]


class _Page(HTMLParser):
    def __init__(self):
        super().__init__()
        self.links, self.images, self.ids = [], [], set()

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if "id" in a:
            self.ids.add(a["id"])
        if tag == "a" and a.get("href"):
            self.links.append(a["href"])
        elif tag in ("img", "script") and a.get("src"):
            (self.images if tag == "img" else self.links).append(a["src"])
        elif tag == "link" and a.get("href"):
            self.links.append(a["href"])


def _parse(path: Path) -> _Page:
    page = _Page()
    page.feed(path.read_text(encoding="utf-8"))
    return page


@pytest.fixture(scope="module")
def site():
    index = SITE / "index.html"
    assert index.exists(), f"{index} is missing: build the site first (make docs)"
    # the pages (not the theme's template fragments copied into _static)
    return {p: _parse(p) for p in SITE.rglob("*.html") if "_static" not in p.parts}


def test_every_local_link_and_anchor_resolves(site):
    broken = []
    for path, page in site.items():
        for ref in page.links + page.images:
            url = urlsplit(ref)
            if url.scheme or url.netloc or ref.startswith(("mailto:", "javascript:")):
                continue
            target = (path.parent / unquote(url.path)).resolve() if url.path else path
            if not target.exists():
                broken.append(f"{path.relative_to(SITE)}: {ref}")
            elif url.fragment and target.suffix == ".html":
                ids = site[target].ids if target in site else _parse(target).ids
                if url.fragment not in ids:
                    broken.append(f"{path.relative_to(SITE)}: {ref} (no such anchor)")
    assert broken == []
    # the pages the issue asks for, and a page per subpackage
    names = {p.relative_to(SITE).as_posix() for p in site}
    for page in ("getting_started.html", "model.html", "reproduction.html",
                 "interchange.html", "dask.html", "changelog.html", "gallery/index.html",
                 "api/index.html", "api/control.html", "api/nonlinear.html"):
        assert page in names, page
    assert len([n for n in names if re.fullmatch(r"gallery/plot_\w+\.html", n)]) >= 10


def _chromium():
    exe = shutil.which("chromium") or shutil.which("chromium-browser")
    assert exe, "Chromium is missing: `make test` installs it (apt-get install -y chromium)"
    return exe


def test_every_image_loads_in_a_real_browser(site, tmp_path):
    """A harness page opens each page with images (and the index) in an iframe, loads every
    image it has as the browser resolves it and counts those that fail to load or decode."""
    pages = sorted({p for p, page in site.items() if page.images} | {SITE / "index.html"})
    harness = tmp_path / "harness.html"
    harness.write_text("""<!doctype html><html><body><script>
const pages = %s;
let images = 0, broken = [], titles = 0;
function load(src) {
  return new Promise(ok => { const im = new Image();
    im.onload = () => ok(im.naturalWidth > 0); im.onerror = () => ok(false); im.src = src; });
}
function open(url) {
  return new Promise(ok => { const f = document.createElement("iframe");
    f.onload = async () => {
      const doc = f.contentDocument;
      if (doc.querySelector("h1")) titles += 1;
      for (const im of doc.querySelectorAll("img")) {
        images += 1;
        if (!(await load(im.src))) broken.push(url + " " + im.getAttribute("src"));
      }
      f.remove(); ok();
    };
    f.src = url; document.body.appendChild(f); });
}
(async () => {
  for (const p of pages) await open(p);
  const out = document.createElement("pre"); out.id = "result";
  out.textContent = JSON.stringify({pages: pages.length, titles, images, broken});
  document.body.appendChild(out);
})();
</script></body></html>""" % json.dumps([p.as_uri() for p in pages]))
    dom = subprocess.run([_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'ud'}",
                          "--allow-file-access-from-files", "--virtual-time-budget=60000",
                          "--dump-dom", harness.as_uri()],
                         capture_output=True, text=True, timeout=300).stdout
    m = re.search(r'<pre id="result">(.*?)</pre>', dom, re.S)
    assert m, "the harness did not finish: " + dom[-500:]
    res = json.loads(m.group(1).replace("&quot;", '"').replace("&amp;", "&"))
    assert res["broken"] == [] and res["titles"] == res["pages"] == len(pages), res
    # every <img> of those pages was tried: the gallery's thumbnails (10) and figures (one or
    # more per example), the model page's four figures
    assert res["images"] == sum(len(site[p].images) for p in pages) >= 24, res


def test_the_index_renders(tmp_path):
    """A screenshot of the index as a reader's browser draws it (kept beside the site as
    screenshot-index.png): a page, not a blank or an error page."""
    shot = SITE.parent / "screenshot-index.png"
    subprocess.run([_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'ud'}",
                    "--window-size=1280,1100", f"--screenshot={shot}",
                    (SITE / "index.html").as_uri()], capture_output=True, timeout=120)
    data = shot.read_bytes()
    assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 50_000, len(data)


#: the window width the layout check runs at [px] (a laptop's; the index screenshot's)
WIDTH = 1280

_OVERFLOW_JS = r"""
const pages = %s;
const out = {};
function clipper(el) {  // the nearest ancestor that clips or scrolls what overflows it
  for (let a = el.parentElement; a; a = a.parentElement)
    if (a.ownerDocument.defaultView.getComputedStyle(a).overflowX !== "visible") return a;
  return null;
}
function name(el) {
  let s = el.tagName.toLowerCase();
  if (typeof el.className === "string" && el.className.trim())
    s += "." + el.className.trim().split(/\s+/).join(".");
  return s;
}
function check(doc) {
  const bad = [];
  const scopes = doc.querySelectorAll("article.bd-article, .prev-next-area, footer.bd-footer");
  for (const scope of scopes) for (const el of [scope, ...scope.querySelectorAll("*")]) {
    if (!el.getClientRects().length) continue;
    const r = el.getBoundingClientRect();
    if (r.width === 0 || r.height === 0) continue;
    const text = (el.innerText || el.getAttribute("src") || "").slice(0, 60);
    if (el.clientWidth > 0 && el.scrollWidth > el.clientWidth + 1) {
      bad.push(`${name(el)} holds ${el.scrollWidth} px in ${el.clientWidth} px: ${text}`);
      continue;
    }
    const a = clipper(el);
    if (a) {
      const ra = a.getBoundingClientRect();
      if (r.right > ra.right + 1 || r.left < ra.left - 1)
        bad.push(`${name(el)} beyond its ${name(a)} by ` +
                 `${Math.round(Math.max(r.right - ra.right, ra.left - r.left))} px: ${text}`);
    }
  }
  return bad;
}
function open(url) {
  return new Promise(ok => { const f = document.createElement("iframe");
    f.style.width = "%dpx"; f.style.height = "900px";
    f.onload = () => setTimeout(() => {
      const bad = check(f.contentDocument);
      if (bad.length) out[url] = bad;
      f.remove(); ok(); }, 200);
    f.src = url; document.body.appendChild(f); });
}
(async () => {
  for (const p of pages) await open(p);
  const pre = document.createElement("pre"); pre.id = "result";
  pre.textContent = JSON.stringify({pages: pages.length, overflowing: out});
  document.body.appendChild(pre);
})();
"""


def test_no_element_is_wider_than_its_container(site, tmp_path):
    """On every gallery and API page, at a window of `WIDTH` px, no element of the article or
    the footer holds more than its box shows (a line of output or code that scrolls out of
    sight, a table wider than its column) or stands beyond the box that clips it (the
    footer's previous / next links, which were cut off on the API pages): a reader sees
    every character without scrolling sideways (issue 35).  The figures themselves are
    checked when the gallery builds (`docs/_scraper.py`: nothing drawn beyond a figure's
    edge)."""
    pages = sorted(p for p in site if p.relative_to(SITE).parts[0] in ("gallery", "api"))
    assert len(pages) > 100, len(pages)
    harness = tmp_path / "harness.html"
    harness.write_text("<!doctype html><html><body><script>"
                       + _OVERFLOW_JS % (json.dumps([p.as_uri() for p in pages]), WIDTH)
                       + "</script></body></html>")
    dom = subprocess.run([_chromium(), *CHROMIUM_FLAGS, f"--user-data-dir={tmp_path / 'ud'}",
                          "--allow-file-access-from-files", "--virtual-time-budget=600000",
                          "--dump-dom", harness.as_uri()],
                         capture_output=True, text=True, timeout=900).stdout
    m = re.search(r'<pre id="result">(.*?)</pre>', dom, re.S)
    assert m, "the harness did not finish: " + dom[-500:]
    res = json.loads(m.group(1).replace("&quot;", '"').replace("&lt;", "<")
                     .replace("&gt;", ">").replace("&amp;", "&"))
    assert res["pages"] == len(pages)
    shown = {Path(urlsplit(u).path).relative_to(SITE).as_posix(): v[:3]
             for u, v in res["overflowing"].items()}
    assert shown == {}, shown
