"""`make live-screenshot`: docs/live.png from a real headless Chromium showing `fsrlab live --virtual`.

Starts the live page on the virtual device (a triangle stress profile), lets it run for a few
cycles, and saves what Debian's chromium renders. Needs `make sysdeps` (chromium, chromium-driver).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

from browser import LiveServer, chromium, text, wait_for  # noqa: E402


def main(out: Path = ROOT / "docs" / "live.png", seconds: float = 10.0) -> int:
    server = LiveServer("--virtual", "--seed", "1", "--window", "50ms", "--period", "4s")
    driver = chromium(1400, 900)
    try:
        driver.get(server.url)
        if not wait_for(lambda: text(driver, "#latest-seq"), timeout_s=30):
            print("live-screenshot: the page showed no data", file=sys.stderr)
            return 1
        time.sleep(seconds)
        driver.save_screenshot(str(out))
    finally:
        driver.quit()
        server.stop()
    print(f"live-screenshot: {out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
