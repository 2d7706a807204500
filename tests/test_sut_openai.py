"""The openai: and http: adapters against a real local HTTP server (real sockets, threads).

The server speaks chat-completions and plays a script per request: messy model
output, 429 with Retry-After, 5xx, slow replies past the deadline, 401s that echo
the key, servers without JSON mode.  Backoff is kept short through the adapters'
own options, not by patching.
"""
from __future__ import annotations

import json
import threading
import time
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

import numpy as np
import pytest

from isu_validate.space import load_space
from isu_validate.sut import SUTConfigError, build_request, open_sut
from isu_validate.sut.http_client import parse_retry_after
from isu_validate.sut.limits import RateLimiter

KEY = "sk-test-abcdefghijklmnopqrstuvwxyz123456"
FAST = {"backoff_s": "0.01", "backoff_max_s": "0.05", "max_retries": "3"}


class ScriptedServer:
    """A chat-completions server: each request takes the next step of ``script``
    (or repeats the last).  A step is a dict: status, body (dict or str), headers, delay_s."""

    def __init__(self):
        self.script: list[dict] = []
        self.requests: list[dict] = []
        self.active = self.max_active = 0
        self._lock = threading.Lock()
        server = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *args):  # keep test output clean
                pass

            def do_POST(self):
                body = json.loads(self.rfile.read(int(self.headers["Content-Length"])))
                with server._lock:
                    server.requests.append({"path": self.path, "headers": dict(self.headers), "body": body})
                    step = server.script.pop(0) if len(server.script) > 1 else server.script[0]
                    server.active += 1
                    server.max_active = max(server.max_active, server.active)
                try:
                    if callable(step):
                        step = step(body, dict(self.headers))
                    time.sleep(step.get("delay_s", 0))
                finally:
                    # done before the reply is written: once the client holds the reply it may send the next
                    # request, and this thread may not have run again yet (a busy machine) to count this one out
                    with server._lock:
                        server.active -= 1
                try:
                    payload = step.get("body", "")
                    data = (payload if isinstance(payload, str) else json.dumps(payload)).encode()
                    self.send_response(step.get("status", 200))
                    for name, value in step.get("headers", {}).items():
                        self.send_header(name, value)
                    self.send_header("Content-Type", "application/json")
                    self.send_header("Content-Length", str(len(data)))
                    self.end_headers()
                    self.wfile.write(data)
                except (BrokenPipeError, ConnectionResetError):
                    pass  # the client gave up (timeout): expected in some tests

        self.httpd = ThreadingHTTPServer(("127.0.0.1", 0), Handler)
        self.httpd.daemon_threads = True
        self.url = f"http://127.0.0.1:{self.httpd.server_address[1]}"
        self.thread = threading.Thread(target=self.httpd.serve_forever, kwargs={"poll_interval": 0.02}, daemon=True)
        self.thread.start()

    def close(self):
        self.httpd.shutdown()
        self.httpd.server_close()


def chat(content, finish_reason="stop", **message):
    return {"status": 200, "body": {"id": "x", "object": "chat.completion", "choices": [
        {"index": 0, "finish_reason": finish_reason, "message": {"role": "assistant", "content": content, **message}}]}}


@pytest.fixture()
def server():
    s = ScriptedServer()
    yield s
    s.close()


@pytest.fixture()
def space():
    return load_space()


@pytest.fixture()
def scene():
    return {"driver_gender": "MALE", "driver_emotion": "HAPPY", "driver_height": "H2", "driver_weight": "W2",
            "phone_position": "NONE", "seat_belt": "YES", "tshirt_colour": "BLACK", "child_seat": "NO",
            "car_lights": "OFF", "external_light": "HIGH", "luggage": "NO", "luggage_orientation": 30.0,
            "phone_codriver_seat": "NO", "colabottle_codriver_seat": "NO", "colacan_codriver_seat": "NO"}


@pytest.fixture()
def image(tmp_path):
    path = tmp_path / "cabin.png"
    path.write_bytes(b"\x89PNG\r\n\x1a\n" + bytes(np.arange(256, dtype=np.uint8)))
    return path


@pytest.fixture()
def with_key(monkeypatch):
    monkeypatch.setenv("TEST_VLM_KEY", KEY)


def open_openai(server, space, **options):
    opts = {"api_key_env": "TEST_VLM_KEY", **FAST, **options}
    timeout = opts.pop("timeout_s", 5.0)
    cache = opts.pop("cache_dir", None)
    repeats = opts.pop("repeats", 1)
    return open_sut(f"openai:test-vlm@{server.url}/v1", space=space, timeout_s=timeout, cache_dir=cache,
                    repeats=repeats, **opts)


MESSY = ("Sure! Looking at the cabin image:\n```json\n{'driver_gender': 'Male', 'driver_emotion': 'happy',\n"
         " 'phone_position': 'no', 'seat_belt': true, 'tshirt_colour': 'Black', 'child_seat': 'No',\n"
         " 'luggage': 'NO', 'phone_codriver_seat': 'No', 'colabottle_codriver_seat': 'no',\n"
         " 'colacan_codriver_seat': 'N/A', 'luggage_colour': 'YELLOW'}\n```\n"
         "Let me know if you need anything else.")


def test_messy_reply_is_parsed_and_request_is_well_formed(server, space, scene, image, with_key):
    server.script = [chat(MESSY)]
    sut = open_openai(server, space)
    request = build_request(space, scene, image, "vqa")
    response = sut.query(request)
    assert response.error is None
    assert response.answers == {"driver_gender": "MALE", "driver_emotion": "HAPPY", "phone_position": "NO",
                                "seat_belt": "YES", "tshirt_colour": "BLACK", "child_seat": "NO", "luggage": "NO",
                                "phone_codriver_seat": "NO", "colabottle_codriver_seat": "NO"}
    # "N/A" is no answer to a YES/NO question without NONE: invalid, not silently NO
    assert response.extra["status"]["colacan_codriver_seat"] == "invalid"
    assert response.extra["outcome"] == "partial"
    assert "luggage_colour" in response.extra["ignored_keys"]  # inactive feature: never scored
    sent = server.requests[0]
    assert sent["path"] == "/v1/chat/completions"
    assert sent["headers"]["Authorization"] == f"Bearer {KEY}"
    parts = sent["body"]["messages"][0]["content"]
    assert parts[0]["type"] == "text" and "seat_belt" in parts[0]["text"] and "luggage_colour" not in parts[0]["text"]
    assert parts[1]["image_url"]["url"].startswith("data:image/png;base64,")
    assert sent["body"]["response_format"] == {"type": "json_object"}
    assert "temperature" not in sent["body"]  # only sent when configured
    assert KEY not in json.dumps(response.extra) and KEY not in response.raw


def test_429_with_retry_after_is_honoured(server, space, scene, image, with_key):
    server.script = [{"status": 429, "body": {"error": "slow down"}, "headers": {"Retry-After": "0.3"}},
                     chat('{"seat_belt": "YES"}')]
    sut = open_openai(server, space)
    start = time.perf_counter()
    response = sut.query(build_request(space, scene, image, "vqa"))
    elapsed = time.perf_counter() - start
    assert response.error is None and response.answers["seat_belt"] == "YES"
    assert len(server.requests) == 2
    assert elapsed >= 0.3  # waited as told, not the 0.01 s backoff
    assert response.extra["meta"]["attempts"] == 2


def test_retry_after_is_capped_and_parsed():
    assert parse_retry_after("2") == 2.0
    assert parse_retry_after("Wed, 21 Oct 2015 07:28:00 GMT", now=1445412470.0) == pytest.approx(10.0)
    assert parse_retry_after("soon") is None and parse_retry_after(None) is None


def test_5xx_are_retried_then_recorded_as_sut_error(server, space, scene, image, with_key):
    server.script = [{"status": 500, "body": "boom"}, {"status": 503, "body": "busy"}, chat('{"seat_belt": "NO"}')]
    sut = open_openai(server, space)
    assert sut.query(build_request(space, scene, image, "vqa")).answers["seat_belt"] == "NO"

    server.requests.clear()
    server.script = [{"status": 502, "body": f"bad gateway for Bearer {KEY}"}]
    response = sut.query(build_request(space, scene, image, "vqa"))
    assert len(server.requests) == 4  # 1 + max_retries
    assert response.error.startswith("HTTP 502") and "gave up after 4 attempts" in response.error
    assert KEY not in response.error and "[REDACTED]" in response.error
    assert response.answers is None


def test_slow_reply_within_deadline_succeeds_and_past_it_times_out(server, space, scene, image, with_key):
    server.script = [dict(chat('{"seat_belt": "YES"}'), delay_s=0.3)]
    sut = open_openai(server, space, timeout_s=2.0)
    assert sut.query(build_request(space, scene, image, "vqa")).answers == {"seat_belt": "YES"}

    server.requests.clear()
    server.script = [dict(chat('{"seat_belt": "YES"}'), delay_s=1.5)]
    sut = open_openai(server, space, timeout_s=0.4, max_retries="1")
    start = time.perf_counter()
    response = sut.query(build_request(space, scene, image, "vqa"))
    assert "timed out after 0.4 s" in response.error
    assert len(server.requests) == 2  # the timeout was retried once
    assert time.perf_counter() - start < 1.5


def test_rejected_key_is_a_configuration_error_without_the_key(server, space, scene, image, with_key):
    server.script = [{"status": 401, "body": {"error": {"message": f"Incorrect API key provided: {KEY}"}}}]
    sut = open_openai(server, space)
    with pytest.raises(SUTConfigError) as info:
        sut.query(build_request(space, scene, image, "vqa"))
    assert "HTTP 401" in str(info.value) and "API key" in str(info.value)
    assert KEY not in str(info.value)
    assert len(server.requests) == 1  # not retried


def test_missing_key_for_openai_itself_fails_at_open(space, monkeypatch):
    monkeypatch.delenv("NO_SUCH_KEY_VAR", raising=False)
    with pytest.raises(SUTConfigError, match="NO_SUCH_KEY_VAR"):
        open_sut("openai:gpt-4o@https://api.openai.com/v1", space=space, api_key_env="NO_SUCH_KEY_VAR")


def test_local_server_without_key_sends_no_authorization(server, space, scene, image, monkeypatch):
    monkeypatch.delenv("TEST_VLM_KEY", raising=False)
    server.script = [chat('{"seat_belt": "YES"}')]
    open_openai(server, space).query(build_request(space, scene, image, "vqa"))
    assert "Authorization" not in server.requests[0]["headers"]


def test_server_without_json_mode_is_asked_again_without_it(server, space, scene, image, with_key):
    def step(body, headers):
        if "response_format" in body:
            return {"status": 400, "body": {"error": {"message": "response_format is not supported by this model"}}}
        return chat('The answer: {"seat_belt": "YES"}')
    server.script = [step]
    sut = open_openai(server, space)
    assert sut.query(build_request(space, scene, image, "vqa")).answers == {"seat_belt": "YES"}
    assert sut.query(build_request(space, scene, image, "vqa")).answers == {"seat_belt": "YES"}
    assert ["response_format" in r["body"] for r in server.requests] == [True, False, False]


def test_refusal_and_content_parts(server, space, scene, image, with_key):
    server.script = [chat(None, refusal="I can't help with identifying people.")]
    response = open_openai(server, space).query(build_request(space, scene, image, "vqa"))
    assert response.error.startswith("refused")

    server.script = [chat([{"type": "text", "text": "A man at the wheel, "}, {"type": "text", "text": "belted."}])]
    response = open_openai(server, space).query(build_request(space, scene, image, "vc"))
    assert response.caption == "A man at the wheel, belted."
    assert "response_format" not in server.requests[-1]["body"]  # captions are free text


def test_prose_refusal_is_unparseable_sut_error(server, space, scene, image, with_key):
    server.script = [chat("I'm sorry, but I can't assist with that request.")]
    response = open_openai(server, space).query(build_request(space, scene, image, "vqa"))
    assert response.error.startswith("unparseable: no JSON object") and response.answers is None


def test_not_a_chat_completion_is_a_sut_error(server, space, scene, image, with_key):
    server.script = [{"status": 200, "body": "<html>proxy login</html>"}]
    response = open_openai(server, space).query(build_request(space, scene, image, "vqa"))
    assert "not a chat completion" in response.error


def test_concurrency_limit_holds_over_real_sockets(server, space, scene, image, with_key):
    server.script = [dict(chat('{"seat_belt": "YES"}'), delay_s=0.15)]
    sut = open_openai(server, space, max_concurrency="1")
    request = build_request(space, scene, image, "vqa")
    threads = [threading.Thread(target=sut.query, args=(request,)) for _ in range(3)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(server.requests) == 3 and server.max_active == 1


def test_rate_limiter_spaces_requests_per_minute():
    now = [0.0]
    waits = []

    def sleep(s):
        waits.append(s)
        now[0] += s
    limiter = RateLimiter(max_concurrency=2, rpm=2, clock=lambda: now[0], sleep=sleep)
    for _ in range(3):
        with limiter.slot():
            pass
    assert waits and sum(waits) == pytest.approx(60.0)
    with pytest.raises(ValueError, match="rpm"):
        RateLimiter(rpm=0)


def test_repeats_and_cache_over_http(server, space, scene, image, with_key, tmp_path):
    server.script = [chat('{"seat_belt": "YES", "luggage": "NO"}'), chat('{"seat_belt": "NO", "luggage": "NO"}'),
                     chat(f'{{"seat_belt": "YES", "luggage": "YES", "note": "{KEY}"}}')]
    sut = open_openai(server, space, repeats=3, cache_dir=tmp_path / "cache")
    request = build_request(space, scene, image, "vqa")
    first = sut.query(request)
    assert first.answers["seat_belt"] == "YES" and first.answers["luggage"] == "NO"
    assert first.extra["consistency_by_feature"]["seat_belt"] == pytest.approx(2 / 3)
    assert len(server.requests) == 3
    again = sut.query(request)  # every repeat comes from the cache: the server is not asked
    assert len(server.requests) == 3 and again.answers == first.answers and all(again.extra["cached"])
    cached = "".join(p.read_text() for p in (tmp_path / "cache").rglob("*.json"))
    assert KEY not in cached and "[REDACTED]" in cached


def test_http_json_adapter_maps_the_reply(server, space, scene, image, monkeypatch):
    server.script = [{"status": 200, "body": {"result": {"prediction": {"belt": "yes", "gender": "female"}}}}]
    sut = open_sut(f"http:{server.url}/isu", space=space, answers_path="result.prediction",
                   key_map="belt:seat_belt,gender:driver_gender", **FAST)
    response = sut.query(build_request(space, scene, image, "vqa"))
    assert response.answers == {"seat_belt": "YES", "driver_gender": "FEMALE"}
    body = server.requests[0]["body"]
    assert body["mode"] == "vqa" and body["image_media_type"] == "image/png" and body["image"]
    assert {q["key"] for q in body["questions"]} == {q.key for q in space.questions(scene)}
    assert all("truth" not in q for q in body["questions"])  # the truth never leaves

    server.script = [{"status": 200, "body": {"text": "a man"}}]
    response = sut.query(build_request(space, scene, image, "vc"))
    assert "caption_path" in response.error  # names the option to set


def test_bad_specs_name_the_fix(space, tmp_path):
    with pytest.raises(SUTConfigError, match="reference train"):
        open_sut("reference", space=space, model_dir=str(tmp_path))
    with pytest.raises(SUTConfigError, match="unknown SUT spec"):
        open_sut("grpc:foo", space=space)
    with pytest.raises(SUTConfigError, match="unknown option"):
        open_sut("http:http://localhost:1/x", space=space, colour="blue")
    with pytest.raises(SUTConfigError, match="full URL"):
        open_sut("http:localhost:1/x", space=space)


def test_unreachable_server_is_a_sut_error_after_retries(space, scene, image, with_key):
    import socket
    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    sut = open_sut(f"openai:test-vlm@http://127.0.0.1:{port}/v1", space=space, timeout_s=2.0,
                   api_key_env="TEST_VLM_KEY", **dict(FAST, max_retries="1"))
    response = sut.query(build_request(space, scene, image, "vqa"))
    assert response.error.startswith("cannot reach http://127.0.0.1") and "gave up after 2 attempts" in response.error
    assert KEY not in response.error


def test_empty_reply_names_the_finish_reason(server, space, scene, image, with_key):
    server.script = [chat("", finish_reason="length")]
    response = open_openai(server, space).query(build_request(space, scene, image, "vc"))
    assert response.error.startswith("empty reply") and "'length'" in response.error and response.caption is None
