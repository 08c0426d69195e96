"""`bench real-leds` fetches lab11's photos (no licence: never shipped); offline, it names the URL."""

import httpx
import pytest

from simulator import bench_real_leds as bench


def test_a_cached_photo_is_read_from_the_cache_without_fetching(tmp_path, monkeypatch):
    (tmp_path / "small_blob.jpg").write_bytes(b"cached")

    def no_network(*args, **kwargs):
        raise AssertionError("fetched although cached")

    monkeypatch.setattr(httpx, "get", no_network)
    assert bench.fetch_photo("small_blob.jpg", tmp_path).read_bytes() == b"cached"


def test_offline_the_error_names_the_url_pinned_to_the_commit(tmp_path, monkeypatch):
    def offline(url, **kwargs):
        raise httpx.ConnectError("Name or service not known")

    monkeypatch.setattr(httpx, "get", offline)
    with pytest.raises(SystemExit) as error:
        bench.fetch_photo("x_0_y_1.27.jpg", tmp_path)
    url = f"https://raw.githubusercontent.com/lab11/vlc-localization/{bench.COMMIT}/processing/samples/x_0_y_1.27.jpg"
    assert url in str(error.value)
    assert not (tmp_path / "x_0_y_1.27.jpg").exists()
