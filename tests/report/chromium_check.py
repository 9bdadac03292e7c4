#!/usr/bin/env python3
"""Opens tunekit's calibration report in a real browser (headless Chromium, Debian's
`chromium` package) and checks what a technician would see:

- every image loads (no broken image: complete, with a natural width);
- no request leaves the file: every request the page makes is a file: or data: URL, the page
  carries a Content-Security-Policy, and that policy blocks a probe image from the network;
- the summary shows a 95 % interval or a basis for every row, and the agreement line for tau.

Usage: chromium_check.py --tunekit EXE --work DIR     (runs `tunekit calibrate --machine sim`)
       chromium_check.py --report FILE                 (checks an existing report.html)
Exit codes: 0 passed, 1 failed, 77 skipped (no chromium on this machine; the reason is printed).

The browser is driven through the DevTools protocol over a pipe (--remote-debugging-pipe: JSON
messages separated by NUL bytes, the browser reads fd 3 and writes fd 4), so no port is opened.
"""
import argparse
import json
import os
import select
import shutil
import subprocess
import sys
import tempfile
import time

CHROMIUM_FLAGS = [
    "--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync",
    "--hide-scrollbars", "--window-size=1100,1600",
]


class Browser:
    def __init__(self, chromium):
        self.profile = tempfile.mkdtemp(prefix="tunekit-chromium-")
        to_r, self.to_w = os.pipe()
        self.from_r, from_w = os.pipe()

        def child_fds():  # the browser reads commands on fd 3 and answers on fd 4
            a, b = os.dup(to_r), os.dup(from_w)
            os.dup2(a, 3)
            os.dup2(b, 4)

        self.proc = subprocess.Popen(
            [chromium, *CHROMIUM_FLAGS, f"--user-data-dir={self.profile}", "--remote-debugging-pipe", "about:blank"],
            preexec_fn=child_fds, close_fds=False, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL)
        os.close(to_r)
        os.close(from_w)
        self.buf = b""
        self.next_id = 0
        self.events = []

    def close(self):
        try:
            self.send("Browser.close", timeout=5)
        except Exception:  # the browser may already be gone
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.profile, ignore_errors=True)

    def _read_message(self, deadline):
        while b"\0" not in self.buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("the browser did not answer in time")
            ready, _, _ = select.select([self.from_r], [], [], left)
            if ready:
                chunk = os.read(self.from_r, 1 << 16)
                if not chunk:
                    raise RuntimeError("the browser closed its DevTools pipe")
                self.buf += chunk
        msg, self.buf = self.buf.split(b"\0", 1)
        return json.loads(msg)

    def send(self, method, params=None, session=None, timeout=30):
        self.next_id += 1
        msg = {"id": self.next_id, "method": method, "params": params or {}}
        if session:
            msg["sessionId"] = session
        os.write(self.to_w, json.dumps(msg).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            m = self._read_message(deadline)
            if m.get("id") == self.next_id:
                if "error" in m:
                    raise RuntimeError(f"{method}: {m['error']}")
                return m.get("result", {})
            self.events.append(m)

    def wait_event(self, method, timeout=30):
        for i, e in enumerate(self.events):
            if e.get("method") == method:
                return self.events.pop(i)
        deadline = time.monotonic() + timeout
        while True:
            m = self._read_message(deadline)
            if m.get("method") == method:
                return m
            self.events.append(m)


def evaluate(browser, session, expression):
    r = browser.send("Runtime.evaluate", {"expression": expression, "returnByValue": True, "awaitPromise": True},
                     session)
    if "exceptionDetails" in r:
        raise RuntimeError(f"evaluation failed: {r['exceptionDetails']}")
    return r["result"].get("value")


def check_report(chromium, report):
    failures = []
    url = "file://" + os.path.abspath(report)
    browser = Browser(chromium)
    try:
        targets = browser.send("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        session = browser.send("Target.attachToTarget", {"targetId": page["targetId"], "flatten": True})["sessionId"]
        for domain in ("Page", "Network", "Runtime"):
            browser.send(f"{domain}.enable", session=session)
        browser.send("Page.navigate", {"url": url}, session)
        browser.wait_event("Page.loadEventFired", timeout=60)

        images = evaluate(browser, session, "Array.from(document.images).map(i => ({alt: i.alt, "
                          "complete: i.complete, width: i.naturalWidth, scheme: i.src.split(':')[0]}))")
        if not images:
            failures.append("the report shows no images")
        for img in images:
            if not (img["complete"] and img["width"] > 0):
                failures.append(f"broken image: {img['alt']}")
            if img["scheme"] != "data":
                failures.append(f"image not embedded in the file ({img['scheme']}:): {img['alt']}")

        csp = evaluate(browser, session, "(document.querySelector('meta[http-equiv=\"Content-Security-Policy\"]') "
                       "|| {}).content || ''")
        if "default-src 'none'" not in csp:
            failures.append(f"no Content-Security-Policy forbidding requests (found: {csp!r})")
        # The policy in force: an image from the network (a local discard port) is refused.
        probe = evaluate(browser, session, """new Promise(done => {
            document.addEventListener('securitypolicyviolation', e => done('blocked ' + e.violatedDirective),
                                      {once: true});
            const i = new Image(); i.src = 'http://127.0.0.1:9/probe.png'; document.body.appendChild(i);
            setTimeout(() => done('not blocked'), 5000); })""")
        if not str(probe).startswith("blocked img-src"):
            failures.append(f"the Content-Security-Policy did not block a network image: {probe}")

        requests = [e["params"]["request"]["url"] for e in browser.events
                    if e.get("method") == "Network.requestWillBeSent"]
        for u in requests:
            if u.split(":", 1)[0] not in ("file", "data") and "127.0.0.1:9/probe.png" not in u:
                failures.append(f"a request left the file: {u}")

        rows = evaluate(browser, session, "Array.from(document.querySelectorAll('#summary tr')).slice(1).map(r => "
                        "Array.from(r.cells).map(c => c.textContent))")
        if not rows:
            failures.append("the summary table is empty")
        for r in rows:
            if len(r) != 4 or not (r[2].startswith("[") or r[2].startswith("designed") or r[2] == "fixed"):
                failures.append(f"summary row without an interval or basis: {r}")
        tau = evaluate(browser, session, "(document.getElementById('agreement-tau') || {}).textContent || ''")
        if "liquefier time constant tau: step response" not in tau or "do NOT agree" in tau:
            failures.append(f"no agreement line for tau (found: {tau!r})")
        print(f"chromium_check: {len(images)} images, {len(rows)} summary rows, {len(requests)} requests, "
              f"CSP probe: {probe}")
    finally:
        browser.close()
    return failures


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--tunekit")
    ap.add_argument("--work")
    ap.add_argument("--report")
    a = ap.parse_args()
    chromium = shutil.which("chromium")
    if not chromium:
        print("SKIPPED: headless-browser check needs Debian's chromium package (scripts/install-deps --tests installs it)")
        return 77
    report = a.report
    if not report:
        if not (a.tunekit and a.work):
            ap.error("give --report FILE, or --tunekit EXE and --work DIR")
        shutil.rmtree(a.work, ignore_errors=True)
        os.makedirs(a.work)
        run = os.path.join(a.work, "run")
        p = subprocess.run([a.tunekit, "calibrate", "--machine", "sim", "--sim", "preset=peek", "--out", run], capture_output=True, text=True,
                           timeout=600)
        if p.returncode != 0:
            print(f"FAILED: tunekit calibrate exited {p.returncode}: {p.stderr}")
            return 1
        report = os.path.join(run, "report.html")
    failures = check_report(chromium, report)
    for f in failures:
        print("FAILED:", f)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
