"""Measure the person's page in a real browser during a running session; take its screenshots.

    python bench/page_in_browser.py --port 8765 --out shots/ --seconds 30

Opens the page (and the console) of a running session (``session ... --display``) in Debian's
headless Chromium through Selenium, at 1920x1080. While the person acts (banner tone "act") it
reads the page's own counters for ``--seconds``: the frame rate (requestAnimationFrame callbacks
per second) and the state-to-screen latency (the wall time of the first frame drawn with a
state minus the wall time the display node sent it: ``performance.timeOrigin +
performance.now()`` against the node's ``time.time()``, one machine, one clock), and how many
states were drawn against how many the sim published in that time (5 Hz). Screenshots are taken
when the robot practises alone, during the countdown to the person's first episode, during an
episode, and of the console; ``--phone`` adds one at 390x844.
"""

import argparse
import json
import pathlib
import sys
import time

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / 'src' / 'hrc_live' / 'test'))
from browser import open_browser, screenshot, set_viewport  # noqa: E402


def banner(driver) -> tuple:
    element = driver.find_element('id', 'banner')
    return element.text, element.get_attribute('class')


def wait(driver, condition, timeout: float, what: str) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        if condition():
            return True
        time.sleep(0.2)
    print(f'gave up waiting for {what} after {timeout:.0f} s (banner: {banner(driver)[0]!r})')
    return False


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--port', type=int, default=8765)
    parser.add_argument('--out', default='shots')
    parser.add_argument('--seconds', type=float, default=30.0,
                        help='measure this long while the person acts')
    parser.add_argument('--wait', type=float, default=3600.0,
                        help='give up waiting for a situation after this long (s)')
    parser.add_argument('--phone', action='store_true', help='also a 390x844 screenshot')
    options = parser.parse_args()
    out = pathlib.Path(options.out)
    out.mkdir(parents=True, exist_ok=True)
    base = f'http://127.0.0.1:{options.port}'
    driver = open_browser(1920, 1080)
    console = open_browser(1280, 900)
    try:
        driver.get(base + '/')
        console.get(base + '/console')
        if wait(driver, lambda: 'learning alone' in banner(driver)[0], 120, 'the robot alone'):
            time.sleep(2.0)
            screenshot(driver).save(out / 'page-robot-alone.png')
            screenshot(console).save(out / 'console-robot-alone.png')
            print('screenshot: the robot practises alone')
        if wait(driver, lambda: banner(driver)[0].startswith('Get ready'), options.wait,
                'the countdown to the first episode'):
            screenshot(driver).save(out / 'page-get-ready.png')
            print(f'screenshot: {banner(driver)[0]}')
        if not wait(driver, lambda: banner(driver)[1] == 'act', options.wait, 'an episode'):
            return 1
        driver.execute_script('window.hrcScene.stats.latencies = []')
        sent_before = driver.execute_script('return window.hrcScene.stats.statesDrawn')
        started = time.monotonic()
        time.sleep(options.seconds / 2)
        screenshot(driver).save(out / 'page-episode.png')
        screenshot(console).save(out / 'console.png')
        time.sleep(options.seconds / 2)
        elapsed = time.monotonic() - started
        stats = driver.execute_script(f'return window.hrcStats({min(options.seconds, 10)})')
        latencies = driver.execute_script('return window.hrcScene.stats.latencies')
        drawn = stats['statesDrawn'] - sent_before
        ordered = sorted(latencies)
        print(json.dumps({
            'seconds': round(elapsed, 1), 'frames_per_second_last_10s': round(stats['fps'], 1),
            'states_drawn': drawn, 'states_per_second': round(drawn / elapsed, 2),
            'latency_ms': {'count': len(ordered),
                           'min': round(ordered[0], 1) if ordered else None,
                           'median': round(stats['latency_median_ms'], 1)
                           if ordered else None,
                           'p95': round(stats['latency_p95_ms'], 1) if ordered else None,
                           'max': round(ordered[-1], 1) if ordered else None}}, indent=1))
        if options.phone:
            set_viewport(driver, 390, 844, mobile=True)
            time.sleep(1.0)
            screenshot(driver).save(out / 'page-phone.png')
    finally:
        driver.quit()
        console.quit()
    return 0


if __name__ == '__main__':
    sys.exit(main())
