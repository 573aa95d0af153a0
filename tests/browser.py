"""The distribution's headless Chromium, driven by Selenium, with the network off: a page
that needs anything but its own file fails to load it. Bokeh's views live in shadow DOM;
``find`` reaches into it."""

from __future__ import annotations

import shutil
from pathlib import Path

CHROMIUM = ("/usr/bin/chromium", "/usr/bin/chromium-browser")
CHROMEDRIVER = ("/usr/bin/chromedriver",)


def executable(candidates) -> str | None:
    for path in candidates:
        if Path(path).is_file():
            return path
    return shutil.which(Path(candidates[0]).name)


def driver(downloads: Path | None = None, width: int = 1500, height: int = 1400):
    """A headless Chromium of the distribution's packages with no network (every host
    resolves to nothing, no proxy reachable), its console kept."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = executable(CHROMIUM)
    for argument in ("--headless=new", "--no-sandbox", "--disable-dev-shm-usage",
                     "--disable-gpu", f"--window-size={width},{height}",
                     "--host-resolver-rules=MAP * ~NOTFOUND", "--proxy-server=127.0.0.1:9",
                     "--no-first-run", "--disable-background-networking"):
        options.add_argument(argument)
    options.set_capability("goog:loggingPrefs", {"browser": "ALL"})
    if downloads is not None:
        options.add_experimental_option("prefs", {
            "download.default_directory": str(downloads),
            "download.prompt_for_download": False})
    return webdriver.Chrome(service=Service(executable(CHROMEDRIVER)), options=options)


def errors(browser) -> list[str]:
    """The console's errors and failed loads since the last call."""
    return [entry["message"] for entry in browser.get_log("browser")
            if entry["level"] in ("SEVERE", "ERROR")]


#: the Bokeh document's models by name, and a search through shadow roots
HELPERS = """
window.model = name => Bokeh.documents[0].get_model_by_name(name);
window.drawn = name => Array.from(Bokeh.index.find_one(model(name)).all_indices);
window.deep = (selector, root = document) => {
  const found = [...root.querySelectorAll(selector)];
  for (const el of root.querySelectorAll('*')) {
    if (el.shadowRoot) found.push(...window.deep(selector, el.shadowRoot));
  }
  return found;
};
"""


def ready(browser, timeout: float = 60.0) -> None:
    """Wait until Bokeh has drawn the page (its document and views exist)."""
    from selenium.webdriver.support.ui import WebDriverWait

    WebDriverWait(browser, timeout).until(lambda b: b.execute_script(
        "return window.Bokeh !== undefined && Bokeh.documents.length > 0 && "
        "Bokeh.index !== undefined && [...Bokeh.index].length > 0"))
    browser.execute_script(HELPERS)
