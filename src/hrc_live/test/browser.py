"""A real headless Chromium (Debian's chromium + chromedriver) driven by Selenium, for the pages.

Not a fixture module of its own: test files import :func:`open_browser` and
:func:`set_viewport`. The viewport is set through the DevTools protocol to exact CSS pixels
with a device scale factor of 1, so a screenshot pixel is a CSS pixel.
"""

import io
import shutil

from PIL import Image

CHROMIUM = shutil.which('chromium') or '/usr/bin/chromium'
CHROMEDRIVER = shutil.which('chromedriver') or '/usr/bin/chromedriver'


def open_browser(width=1920, height=1080):
    """Return a headless Chromium WebDriver with a ``width`` x ``height`` viewport."""
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    options = webdriver.ChromeOptions()
    options.binary_location = CHROMIUM
    for argument in ('--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
                     '--hide-scrollbars', f'--window-size={width},{height}',
                     '--force-device-scale-factor=1'):
        options.add_argument(argument)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=options)
    set_viewport(driver, width, height)
    return driver


def set_viewport(driver, width, height, mobile=False):
    """Set the viewport to ``width`` x ``height`` CSS px (scale factor 1)."""
    driver.execute_cdp_cmd('Emulation.setDeviceMetricsOverride', {
        'width': width, 'height': height, 'deviceScaleFactor': 1, 'mobile': mobile})


def screenshot(driver) -> Image.Image:
    """Return the viewport as an RGB image."""
    return Image.open(io.BytesIO(driver.get_screenshot_as_png())).convert('RGB')
