"""Check the built site in a real browser (Debian's headless Chromium through chromedriver).

For the site's index, the gallery's index and one gallery example: open the page, take a
screenshot (docs/_build/screenshots/), and fail unless every <img> has loaded (naturalWidth > 0)
and every link, image, stylesheet and script of the page that points to a local file exists.
Exit 0 when all pages pass, 1 otherwise (one line per problem), 2 when the browser is missing.

    python docs/check_site.py [--html docs/_build/html] [--page auto_examples/plot_02_finger.html]
"""

from __future__ import annotations

import argparse
import shutil
import sys
from pathlib import Path
from urllib.parse import unquote, urlsplit

DOCS = Path(__file__).resolve().parent
PAGES = ("index.html", "auto_examples/index.html", "auto_examples/plot_02_finger.html")
BROWSERS = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
DRIVERS = ("/usr/bin/chromedriver", "/usr/lib/chromium/chromedriver")

# every local reference of the page (href/src), and the state of each <img>
PAGE_SCRIPT = """
const refs = [];
for (const el of document.querySelectorAll('[href], [src]')) {
  for (const name of ['href', 'src']) {
    const value = el.getAttribute(name);
    if (value) refs.push([el.tagName, new URL(value, document.baseURI).href]);
  }
}
const images = Array.from(document.images).map(img => [img.currentSrc || img.src, img.complete,
                                                       img.naturalWidth, img.naturalHeight]);
return [refs, images, document.documentElement.scrollHeight];
"""


def _first(paths):
    return next((p for p in paths if Path(p).exists()), None) or shutil.which(Path(paths[0]).name)


def browser():
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    binary, driver = _first(BROWSERS), _first(DRIVERS)
    if not binary or not driver:
        print("check_site: Debian's chromium and chromium-driver are needed "
              "(apt-get install chromium chromium-driver)", file=sys.stderr)
        sys.exit(2)
    options = webdriver.ChromeOptions()
    options.binary_location = binary
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage", "--disable-gpu",
                     "--hide-scrollbars", "--force-device-scale-factor=1",
                     "--window-size=1280,900"):
        options.add_argument(argument)
    return webdriver.Chrome(service=Service(executable_path=driver), options=options)


def local_file(url: str, root: Path) -> Path | None:
    """The file a file:// URL names (None for other schemes and in-page anchors)."""
    parts = urlsplit(url)
    if parts.scheme != "file":
        return None
    return Path(unquote(parts.path)) if parts.path else None


def check_page(driver, html: Path, page: str, shots: Path) -> list[str]:
    from selenium.webdriver.support.ui import WebDriverWait

    path = html / page
    if not path.exists():
        return [f"{page}: not built"]
    driver.set_window_size(1280, 900)
    driver.get(path.as_uri())
    # images below the fold load as well: scroll through, then wait until every one is done
    driver.execute_script("document.querySelectorAll('img[loading]').forEach("
                          "i => i.removeAttribute('loading'));")
    height = driver.execute_script("return document.documentElement.scrollHeight")
    for y in range(0, height, 800):
        driver.execute_script(f"window.scrollTo(0, {y})")
    driver.execute_script("window.scrollTo(0, 0)")
    WebDriverWait(driver, 30).until(lambda d: d.execute_script(
        "return Array.from(document.images).every(i => i.complete)"))
    refs, images, height = driver.execute_script(PAGE_SCRIPT)
    problems = []
    for src, complete, width, _ in images:
        if not complete or width <= 0:
            problems.append(f"{page}: picture does not load: {src}")
    seen = set()
    for tag, url in refs:
        target = local_file(url, html)
        if target is None or target in seen:
            continue
        seen.add(target)
        if not target.exists():
            problems.append(f"{page}: <{tag.lower()}> points to a missing file: {url}")
    shots.mkdir(parents=True, exist_ok=True)
    shot = shots / (page.replace("/", "_").removesuffix(".html") + ".png")
    driver.set_window_size(1280, min(max(height, 900), 6000))
    driver.save_screenshot(str(shot))
    print(f"check_site: {page}: {len(images)} pictures, all loaded"
          if not any("picture" in p for p in problems) else f"check_site: {page}: FAILED",
          f"({len(seen)} local files referenced); screenshot {shot}")
    if page == "index.html" and not images:
        problems.append(f"{page}: expected the front page's picture, found no <img>")
    if "auto_examples/plot_" in page and not images:
        problems.append(f"{page}: expected the example's pictures, found no <img>")
    return problems


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--html", type=Path, default=DOCS / "_build" / "html")
    parser.add_argument("--screenshots", type=Path, default=DOCS / "_build" / "screenshots")
    parser.add_argument("--page", action="append",
                        help=f"pages to check (default: {', '.join(PAGES)})")
    args = parser.parse_args(argv)
    driver = browser()
    problems = []
    try:
        for page in args.page or PAGES:
            problems += check_page(driver, args.html.resolve(), page, args.screenshots)
    finally:
        driver.quit()
    for problem in problems:
        print(f"check_site: {problem}", file=sys.stderr)
    print(f"check_site: {'OK' if not problems else f'{len(problems)} problem(s)'}")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
