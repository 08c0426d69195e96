"""The figures of docs/reliability.md "Second hardening pass", at the probe's scale (not a test: minutes each).

    PYTHONPATH=$PWD python -m tests.server.api.stall_figures CASE [N [M]] [--server-tree DIR]

CASE 8 (two 40-view calibrations, a locate), 9 N DELAY (N pictures, a locate DELAY s later), 10 STREAMS DEVICES,
11 (long EXIF make: detail, board, header), 14 ROUNDS (map changes while locating). `--server-tree DIR` runs
the server from another checkout (for example main, for the "before" column); the client is this tree's.
"""

import asyncio
import os
import statistics
import sys
import threading
import time

import httpx

from simulator.local_server import LocalServer
from tests.server.api import test_stalls as t

if "--server-tree" in sys.argv:
    at = sys.argv.index("--server-tree")
    os.environ["PYTHONPATH"] = sys.argv[at + 1]  # the server child's code; this process keeps its own
    os.chdir(sys.argv[at + 1])  # `python -m` puts the working folder first on the child's path
    del sys.argv[at : at + 2]
case = sys.argv[1]
with LocalServer("--api-key", t.API_KEY, "--pipeline-threads", "2", "--log-level", "warning") as server:
    base = t._kib(server.pid, "VmHWM")
    if case == "8":
        spec_, views = t.big_views(40)
        body = t.CalibrationRequest(board=spec_, views=views, device="xiaomi-mi8-front").model_dump_json().encode()
        answers = []
        ws = [threading.Thread(target=t._calibrate, args=(server, body, answers)) for _ in range(2)]
        for w in ws:
            w.start()
            time.sleep(0.3)
        time.sleep(1.5)
        r, s = t._locate_dark(server, timeout=300)
        print("case 8 locate", r.status_code, f"{s:.1f} s")
        for w in ws:
            w.join()
        print("calibrations", [(a.status_code, round(b, 1)) for a, b in answers])
    elif case == "9":
        meta = t.FrameMeta.model_validate_json(t.FIXTURE.read_text())
        device = "pics"
        headers = {
            "Content-Type": "application/octet-stream",
            "X-Lumipose-Device": device,
            t.FRAME_HEADER: meta.model_dump_json(by_alias=True, exclude_none=True),
        }
        httpx.post(
            f"{server.url}/v1/locate", content=t.FIXTURE.with_suffix(".y").read_bytes(), headers=headers, timeout=60
        )
        seq = httpx.get(f"{server.url}/v1/live/devices/{device}/frames").json()[0]["seq"]
        url = f"{server.url}/v1/live/devices/{device}/frames/{seq}.png"

        async def flood():
            n = int(sys.argv[2]) if len(sys.argv) > 2 else 300
            async with httpx.AsyncClient(timeout=300, limits=httpx.Limits(max_connections=n)) as c:
                s0 = time.perf_counter()
                await c.get(url)
                print(f"one picture {1000 * (time.perf_counter() - s0):.0f} ms")
                asks = [asyncio.create_task(c.get(url)) for _ in range(n)]
                await asyncio.sleep(float(sys.argv[3]) if len(sys.argv) > 3 else 0.5)
                r, s = await asyncio.to_thread(t._locate_dark, server, None, 300)
                answers = await asyncio.gather(*asks)
            print(
                "case 9 locate",
                r.status_code,
                f"{s:.1f} s",
                "pictures",
                {k: [a.status_code for a in answers].count(k) for k in {a.status_code for a in answers}},
            )

        asyncio.run(flood())
    elif case == "10":
        data, headers = t._dark()
        n_devices = int(sys.argv[3]) if len(sys.argv) > 3 else 300

        async def fill():
            async with httpx.AsyncClient(timeout=60) as c:
                for st in range(0, n_devices, 20):
                    await asyncio.gather(
                        *(
                            c.post(
                                f"{server.url}/v1/locate",
                                content=data,
                                headers={**headers, "X-Lumipose-Device": f"d-{n}"},
                            )
                            for n in range(st, st + 20)
                        )
                    )

        asyncio.run(fill())
        base = t._kib(server.pid, "VmHWM")
        n_streams = int(sys.argv[2]) if len(sys.argv) > 2 else 40

        async def streams():
            async with httpx.AsyncClient(timeout=httpx.Timeout(60), limits=httpx.Limits(max_connections=300)) as c:
                opened = [
                    await c.send(c.build_request("GET", f"{server.url}/v1/live/events"), stream=True)
                    for _ in range(n_streams)
                ]
                firsts = [asyncio.create_task(t._first_devices_event(r)) for r in opened if r.status_code == 200]
                probes = []
                for _ in range(10):
                    s0 = time.perf_counter()
                    await c.get(f"{server.url}/healthz", timeout=60)
                    probes.append(time.perf_counter() - s0)
                    await asyncio.sleep(0.05)
                await asyncio.gather(*firsts)
                for r in opened:
                    await r.aclose()
                return [r.status_code for r in opened], probes

        st, probes = asyncio.run(streams())
        print(
            "case 10 streams",
            {k: st.count(k) for k in set(st)},
            f"healthz median {statistics.median(probes) * 1000:.0f} ms max {max(probes) * 1000:.0f} ms",
            f"peak +{(t._kib(server.pid, 'VmHWM') - base) / 1024:.0f} MB",
            f"rss now +{(t._kib(server.pid, 'VmRSS') - base) / 1024:.0f} MB",
        )
    elif case == "11":
        photo = t._photo_with_long_make(4 * 2**20)
        for _ in range(4):
            r = httpx.post(
                f"{server.url}/v1/locate",
                content=photo,
                timeout=60,
                headers={"Content-Type": "image/png", "X-Lumipose-Device": "exif"},
            )
        print("case 11 status", r.status_code, "detail chars", len(r.json()["camera_used"]["detail"]))
        b = httpx.get(f"{server.url}/v1/live/devices", timeout=60)
        try:
            a = httpx.post(
                f"{server.url}/v1/locate",
                content=photo,
                params={"annotate": 1},
                timeout=60,
                headers={"Content-Type": "image/png"},
            )
            header = len(a.headers.get(t.RESULT_HEADER, ""))
        except httpx.RemoteProtocolError as e:
            header = f"unreadable by httpx ({e})"
        print(
            "GET devices",
            len(b.content),
            "header",
            header,
            f"peak +{(t._kib(server.pid, 'VmHWM') - base) / 1024:.0f} MB",
            f"rss +{(t._kib(server.pid, 'VmRSS') - base) / 1024:.0f} MB",
        )
    elif case == "14":
        statuses, problems = t._race_maps(server.url, rounds=int(sys.argv[2]) if len(sys.argv) > 2 else 40)
        print("case 14 locates", len(statuses), "non-200", len(problems), problems[:2])
