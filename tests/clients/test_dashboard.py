"""test_dashboard.py URL SCENARIO TOKEN - the dashboard in headless Chromium against a running polydemd:
the submit page loads an example and sends a pasted scenario, the jobs page lists the job and its
progress reaches 100%, the job page's plots and 3D viewer render (pixels other than the
background in each canvas's screenshot), and an invalid scenario shows the field error next to
its path. The daemon wants TOKEN: without it the jobs page says so; typed into the token field
it is kept and used by every page. Prints ok/FAIL lines; the caller prints the summary. Exit status: failures (0 = all ok).
"""

import json
import os
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from cdp import Browser, CdpError, count_near, count_non_background  # noqa: E402

URL = sys.argv[1].rstrip("/")
SCENARIO = open(sys.argv[2]).read()
TOKEN = sys.argv[3]
SHOTS = os.environ.get("SHOTS")  # a directory to keep screenshots in, for a look by eye
failed = 0


def ok(name):
    print("ok   " + name, flush=True)


def bad(name, why):
    global failed
    failed += 1
    print("FAIL %s: %s" % (name, why), flush=True)


def step(name, fn):
    """Runs one check; a CdpError or AssertionError fails it. Returns fn's value or None."""
    try:
        v = fn()
        ok(name)
        return v
    except (CdpError, AssertionError) as e:
        bad(name, e)
        return None


def set_editor(page, text):
    page.eval("(() => { const t = document.getElementById('scenario'); t.value = %s;"
              " t.dispatchEvent(new Event('input')); })()" % json.dumps(text))


def shot(page, selector, name):
    png = page.screenshot_of(selector)
    if SHOTS:
        with open(os.path.join(SHOTS, name + ".png"), "wb") as f:
            f.write(png)
    return png


def painted(page, selector, name, at_least):
    busy, total = count_non_background(shot(page, selector, name))
    assert busy >= at_least * total, "%s: %d of %d pixels differ from the background (want >= %.1f%%)" % (
        selector, busy, total, 100 * at_least)
    return busy, total


def main():
    t0 = time.monotonic()
    with Browser() as b:
        page = b.new_page(URL + "/index.html")

        def token():
            page.wait_for("(document.getElementById('message') || {}).textContent"
                          " && document.getElementById('message').textContent.includes('token')", 10)
            page.eval("(() => { const t = document.getElementById('token'); t.value = %s;"
                      " t.dispatchEvent(new Event('change')); })()" % json.dumps(TOKEN))
            page.wait_for("document.getElementById('message').className.includes('hidden')"
                          " && !!document.querySelector('#jobs-body td.empty')", 10)
        step("token_field", token)
        page.goto(URL + "/submit.html")
        step("submit_page_loads", lambda: page.wait_for(
            "document.querySelectorAll('#example option').length > 1 && !!document.querySelector('header.top .brand')", 15))

        def example():
            page.eval("(() => { const s = document.getElementById('example'); s.value = 'collision';"
                      " s.dispatchEvent(new Event('change')); })()")
            page.wait_for("document.getElementById('scenario').value.includes('\"collision\"')", 10)
            page.wait_for("(document.querySelector('#validation .verdict') || {}).textContent === 'Valid scenario'", 15)
        step("example_loads_and_validates", example)

        # the field error next to its path: friction must be >= 0
        invalid = json.loads(SCENARIO)
        invalid["interactions"][0]["friction"] = -1

        def field_error():
            set_editor(page, json.dumps(invalid, indent=2))
            page.wait_for("!!document.querySelector('.field-error[data-path=\"/interactions/0/friction\"]')", 15)
            text = page.eval("document.querySelector('.field-error[data-path=\"/interactions/0/friction\"]').innerText")
            assert "/interactions/0/friction" in text and len(text) > len("/interactions/0/friction") + 3, text
            page.eval("document.querySelector('.field-error .path').click()")
            sel = page.eval("(() => { const t = document.getElementById('scenario');"
                            " return t.value.slice(t.selectionStart, t.selectionEnd); })()")
            assert '"friction"' in sel, "clicking the path selects %r" % sel
        step("invalid_scenario_shows_field_error", field_error)

        # Submit anyway: POST /v1/jobs names the field in the wrapped body (/scenario/...), shown
        # at the editor's path and line, not at line 1
        def submit_error():
            page.eval("document.getElementById('submit').click()")
            page.wait_for("(document.getElementById('message') || {}).textContent"
                          " && document.getElementById('message').textContent.includes('not submitted')", 15)
            paths = page.eval("[...document.querySelectorAll('.field-error')].map(e => e.dataset.path).join(' ')")
            assert paths == "/interactions/0/friction", "error paths %r" % paths
            where = page.eval("document.querySelector('.field-error .where').textContent")
            lines = json.dumps(invalid, indent=2).split("\n")
            line = next(n for n, text in enumerate(lines, 1) if '"friction"' in text)
            assert where == "line %d" % line, "shown at %r, the field is on line %d" % (where, line)
        step("submit_error_at_field_line", submit_error)

        def syntax_error():
            set_editor(page, '{"time": {"dt": 1e-6,,}}')
            page.wait_for("(document.querySelector('.field-error') || {}).innerText"
                          " && document.querySelector('.field-error').innerText.includes('line 1')", 10)
        step("syntax_error_shows_line", syntax_error)

        def submit():
            set_editor(page, SCENARIO)
            page.eval("document.getElementById('tags').value = 'browser-test'")
            page.wait_for("(document.querySelector('#validation .verdict') || {}).textContent === 'Valid scenario'", 15)
            page.eval("document.getElementById('submit').click()")
            page.wait_for("location.pathname.endsWith('index.html') && location.search.includes('highlight=')", 15)
            return page.eval("new URLSearchParams(location.search).get('highlight')")
        job_id = step("submit_page_submits", submit)
        if not job_id:
            return
        row = "document.querySelector('tr[data-id=\"%s\"]')" % job_id

        def listed():
            page.wait_for("!!" + row, 15)
            text = page.eval(row + ".innerText")
            assert "quick-collision" in text and "browser-test" in text, text
        step("jobs_page_lists_the_job", listed)

        def completes():
            page.wait_for(row + " && " + row + ".dataset.status === 'succeeded'"
                          " && " + row + ".querySelector('.bar-text').textContent === '100%'", 60)
        step("progress_reaches_100_percent", completes)

        def filters():
            page.eval("(() => { const s = document.getElementById('filter-status'); s.value = 'failed';"
                      " s.dispatchEvent(new Event('change')); })()")
            page.wait_for("!" + row + " && !!document.querySelector('#jobs-body td.empty')", 10)
            page.eval("(() => { const s = document.getElementById('filter-status'); s.value = 'succeeded';"
                      " s.dispatchEvent(new Event('change')); })()")
            page.wait_for("!!" + row, 10)
        step("status_filter", filters)

        page.goto(URL + "/job.html?id=" + job_id)

        def plots():
            page.wait_for("document.getElementById('plot-note').textContent.includes('stats rows')", 20)
            page.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
            out = []
            for p in ("ke", "contacts"):  # the first series is drawn in #1f6feb (plot.js)
                n = count_near(shot(page, "#plot-" + p, "plot-" + p), (0x1f, 0x6f, 0xeb))
                assert n >= 60, "#plot-%s: %d pixels of the series colour, want >= 60" % (p, n)
                out.append(n)
            # the five stages in plot.js's first five colours: one stage's line alone may lie
            # along the axis (integrate took 39 pixels in one run), all five together may not
            png = shot(page, "#plot-stages", "plot-stages")
            n = sum(count_near(png, c) for c in ((0x1f, 0x6f, 0xeb), (0xd1, 0x24, 0x2f),
                                                 (0x1a, 0x7f, 0x37), (0x9a, 0x67, 0x00),
                                                 (0x82, 0x50, 0xdf)))
            assert n >= 60, "#plot-stages: %d pixels of the stages' colours, want >= 60" % n
            out.append(n)
            return out
        step("job_page_plots_render", plots)

        def viewer():
            page.wait_for("document.getElementById('frame-label').textContent.includes('frame 0')", 20)
            page.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
            return painted(page, "#viewer canvas", "viewer", 0.002)
        step("job_page_viewer_renders", viewer)

        def slider():
            last = page.eval("document.getElementById('frame').max")
            assert int(last) >= 1, "the slider has %s frames" % last
            page.eval("(() => { const s = document.getElementById('frame'); s.value = s.max;"
                      " s.dispatchEvent(new Event('input')); })()")
            page.wait_for("document.getElementById('frame-label').textContent.startsWith('frame %s ')" % last, 10)
            page.eval("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(r)))")
            shot(page, "#viewer canvas", "viewer-last")  # the moving wall turned (SHOTS: by eye)
        step("time_slider_shows_last_frame", slider)

        def downloads():
            href = page.eval("document.getElementById('dl-result').href")
            assert href.endswith("/v1/jobs/%s/result" % job_id), href
        step("download_links", downloads)

        # a longer job: live progress over SSE on the jobs page, then Cancel and Delete
        longer = json.loads(SCENARIO)
        # long enough (~1e6 steps) that no machine finishes it before the page sees it
        # running with progress; it is cancelled below, so the length costs nothing
        longer["time"]["duration"] = 1.0
        longer["time"]["output_interval"] = 0.01
        longer["name"] = "longer-collision"

        def live():
            page.goto(URL + "/index.html")
            jid = page.eval("fetch('/v1/jobs', {method: 'POST', headers: {'Content-Type': 'application/json',"
                            " Authorization: 'Bearer ' + localStorage.getItem('polydem.token')}, body: %s})"
                            ".then(r => r.json()).then(j => j.id)" % json.dumps(json.dumps({"scenario": longer})))
            r = "document.querySelector('tr[data-id=\"%s\"]')" % jid
            page.wait_for("!!%s && %s.dataset.status === 'running' && (window.polydemEvents || 0) > 0"
                          " && %s.querySelector('.bar-text').textContent !== '0%%'" % (r, r, r), 20)
            page.eval("window.confirm = () => true")
            page.eval(r + ".querySelector('button').click()")  # Cancel
            page.wait_for(r + " && " + r + ".dataset.status === 'cancelled'", 10)
            page.eval(r + ".querySelector('button').click()")  # Delete
            page.wait_for("!" + r, 10)
        step("live_progress_cancel_delete", live)

        errors = [m for m in page.console() if m.startswith("exception") or m.startswith("console.error")]
        if errors:
            bad("no_script_errors", "; ".join(errors)[:600])
        else:
            ok("no_script_errors")
    print("   (browser test took %.1f s)" % (time.monotonic() - t0))


if __name__ == "__main__":
    try:
        main()
    except CdpError as e:
        bad("browser", e)
    sys.exit(1 if failed else 0)
