"""Browser tests: generated HTML (reports, pages) opened in headless Chromium and checked on the rendered DOM."""
