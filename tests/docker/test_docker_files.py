"""Static checks of the Docker files (no engine here; scripts/docker_check.sh runs their install steps)."""

import re
from pathlib import Path

import yaml

from server.api.config import Settings

ROOT = Path(__file__).parents[2]
DOCKERFILE = (ROOT / "docker" / "Dockerfile").read_text()


def test_every_copied_source_exists_and_holds_the_packages():
    copied = [source for line in re.findall(r"^COPY (?!--)(.+)$", DOCKERFILE, re.M) for source in line.split()[:-1]]
    assert copied and all((ROOT / source).exists() for source in copied), copied
    packages = re.search(r'include = \[(.+)\]', (ROOT / "pyproject.toml").read_text())[1]
    for package in re.findall(r'"(\w+)\*"', packages):
        assert package in copied, f"the image would lack the package {package}"


def test_runtime_is_non_root_with_a_healthcheck_and_the_data_volume():
    runtime = DOCKERFILE.split("\nFROM ")[-1]
    assert re.search(r"^USER (?!root)\w+", runtime, re.M)
    assert "HEALTHCHECK" in runtime and "/healthz" in runtime
    env = dict(re.findall(r"(LUMIPOSE_\w+)=(\S+)", runtime))
    assert env["LUMIPOSE_DATA_DIR"] == "/data" and "VOLUME /data" in runtime
    assert set(env) <= {f"LUMIPOSE_{name.upper()}" for name in Settings.model_fields}, "unknown setting"


def test_compose_files_build_the_image_and_mount_the_data_volume():
    for name in ("compose.yaml", "compose.replicas.yaml"):
        compose = yaml.safe_load((ROOT / "docker" / name).read_text())
        service = compose["services"]["lumipose"]
        assert (ROOT / "docker" / service["build"]["context"] / service["build"]["dockerfile"]).is_file()
        volume, mount = service["volumes"][0].split(":")
        assert mount == "/data" and volume in compose["volumes"]
        settings = {f"LUMIPOSE_{field.upper()}" for field in Settings.model_fields}
        assert set(service["environment"]) <= settings, name


def test_balancer_takes_every_upload_the_service_takes():
    conf = (ROOT / "docker" / "nginx.conf").read_text()  # its balancing: tests/deployment/test_manifests.py
    limit_mb = int(re.search(r"client_max_body_size (\d+)m", conf)[1])
    assert limit_mb >= Settings().max_upload_mb, "nginx would refuse uploads the service accepts"
