"""Static checks of the replica deployments (deploy/k8s, docker/compose.replicas.yaml, docker/nginx.conf): the
names, ports and settings each file uses agree with the service's Settings and with the other files."""

import re
from pathlib import Path
from urllib.parse import urlsplit

import yaml

from server.api.config import Settings

ROOT = Path(__file__).parents[2]
K8S = ROOT / "deploy" / "k8s"


def _k8s_objects() -> dict[tuple[str, str], dict]:
    """(kind, name) -> object, of every file the kustomization lists (and only those)."""
    listed = yaml.safe_load((K8S / "kustomization.yaml").read_text())["resources"]
    assert sorted(listed) == sorted(p.name for p in K8S.glob("*.yaml") if p.name != "kustomization.yaml")
    objects = [doc for name in listed for doc in yaml.safe_load_all((K8S / name).read_text()) if doc]
    return {(doc["kind"], doc["metadata"]["name"]): doc for doc in objects}


def _container(deployment: dict) -> dict:
    (container,) = deployment["spec"]["template"]["spec"]["containers"]
    return container


def _env(container: dict) -> dict[str, str]:
    return {item["name"]: item["value"] for item in container["env"] if "value" in item}


def _service_port(service: dict, container: dict) -> int:
    """The Service's port, checked to lead to one of the container's named ports."""
    (port,) = service["spec"]["ports"]
    named = {p["name"]: p["containerPort"] for p in container["ports"]}
    assert port["targetPort"] in named, f"{service['metadata']['name']}: targetPort {port['targetPort']} not a port"
    return port["port"]


def test_the_service_pods_are_configured_by_real_settings_and_reach_redis():
    objects = _k8s_objects()
    deployment, service = objects["Deployment", "lumipose"], objects["Service", "lumipose"]
    container = _container(deployment)
    env = _env(container)
    settings = Settings(**{name.removeprefix("LUMIPOSE_").lower(): value for name, value in env.items()})
    secrets = {item["name"] for item in container["env"] if "valueFrom" in item}
    assert secrets == {"LUMIPOSE_API_KEY"} and env.keys() | secrets <= {f"LUMIPOSE_{f.upper()}" for f in
                                                                          Settings.model_fields}
    assert deployment["spec"]["replicas"] == 3
    assert service["spec"]["selector"].items() <= deployment["spec"]["template"]["metadata"]["labels"].items()
    assert container["ports"][0]["containerPort"] == settings.port == _service_port(service, container)
    for probe in ("readinessProbe", "livenessProbe"):
        assert container[probe]["httpGet"]["path"] == "/healthz", probe
    assert {"cpu"} <= container["resources"]["requests"].keys() & container["resources"]["limits"].keys()

    redis_url = urlsplit(settings.redis)
    redis, redis_service = objects["Deployment", "lumipose-redis"], objects["Service", "lumipose-redis"]
    assert redis_url.scheme == "redis" and redis_url.hostname == "lumipose-redis"
    assert redis_url.port == _service_port(redis_service, _container(redis))
    assert redis_service["spec"]["selector"].items() <= redis["spec"]["template"]["metadata"]["labels"].items()
    args = " ".join(_container(redis)["args"])
    assert "--maxmemory-policy volatile-lru" in args and re.search(r"--maxmemory \d+mb", args)


def test_the_data_folder_is_one_shared_volume_and_the_autoscaler_scales_the_service_on_cpu():
    objects = _k8s_objects()
    deployment = objects["Deployment", "lumipose"]
    pod = deployment["spec"]["template"]["spec"]
    (mount,) = _container(deployment)["volumeMounts"]
    (volume,) = [v for v in pod["volumes"] if v["name"] == mount["name"]]
    claim = objects["PersistentVolumeClaim", volume["persistentVolumeClaim"]["claimName"]]
    assert mount["mountPath"] == _env(_container(deployment))["LUMIPOSE_DATA_DIR"]
    assert claim["spec"]["accessModes"] == ["ReadWriteMany"], "every pod writes samples into it"
    uid = re.search(r"--uid (\d+)", (ROOT / "docker" / "Dockerfile").read_text())[1]
    assert pod["securityContext"]["runAsUser"] == pod["securityContext"]["fsGroup"] == int(uid)

    autoscaler = objects["HorizontalPodAutoscaler", "lumipose"]
    assert autoscaler["apiVersion"] == "autoscaling/v2"
    assert autoscaler["spec"]["scaleTargetRef"] == {"apiVersion": "apps/v1", "kind": "Deployment", "name": "lumipose"}
    assert autoscaler["spec"]["minReplicas"] == deployment["spec"]["replicas"] < autoscaler["spec"]["maxReplicas"]
    (metric,) = autoscaler["spec"]["metrics"]
    assert metric["resource"] == {"name": "cpu", "target": {"type": "Utilization", "averageUtilization": 70}}


def test_compose_replicas_share_the_redis_service_it_runs():
    compose = yaml.safe_load((ROOT / "docker" / "compose.replicas.yaml").read_text())
    services = compose["services"]
    redis_url = urlsplit(Settings(redis=services["lumipose"]["environment"]["LUMIPOSE_REDIS"]).redis)
    assert redis_url.hostname in services and redis_url.hostname in services["lumipose"]["depends_on"]
    command = " ".join(services[redis_url.hostname]["command"])
    assert services[redis_url.hostname]["image"].startswith("redis:7")
    assert "--maxmemory-policy volatile-lru" in command and re.search(r"--maxmemory \d+mb", command)


def test_nginx_balances_the_service_without_stickiness_and_passes_refusals_on():
    conf = (ROOT / "docker" / "nginx.conf").read_text()
    upstream = re.search(r"upstream lumipose \{(.*?)\}", conf, re.S)[1]
    directives = [line.split("#")[0].strip() for line in upstream.splitlines()]
    assert "least_conn;" in directives and not any(d.startswith("hash") for d in directives)
    assert re.search(r"proxy_next_upstream error\b", conf)
