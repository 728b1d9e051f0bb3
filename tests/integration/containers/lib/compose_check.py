"""Consistency of deploy/compose.yaml with the container DDS profile.

The compose file cannot be run by Debian 12's podman-compose (it ignores
ipv4_address), so the harness starts the same containers itself; this check
keeps the two descriptions from drifting: every service of the compose file
is a peer of deploy/cyclonedds/container.xml and vice versa, every container
names every other in /etc/hosts with the address the other really has, the
network is internal, and the cell's database is on a named volume.
Prints what is wrong and exits 1; exits 0 silently when all holds.
"""
import sys
import xml.etree.ElementTree as ET

import yaml


def main(compose_path, profile_path):
    errors = []
    compose = yaml.safe_load(open(compose_path))
    services = compose.get("services", {})
    ns = {"c": "https://cdds.io/config"}
    peers = {p.get("address") for p in ET.parse(profile_path).getroot().iterfind(".//c:Peer", ns)}
    if set(services) != peers:
        errors.append(f"compose services {sorted(services)} != DDS peers {sorted(peers)}")
    address = {}
    for name, svc in services.items():
        for net, cfg in (svc.get("networks") or {}).items():
            if cfg and "ipv4_address" in cfg:
                address[name] = cfg["ipv4_address"]
    for name, svc in services.items():
        hosts = dict(h.split(":", 1) for h in svc.get("extra_hosts", []))
        if hosts != address:
            errors.append(f"{name}: extra_hosts {hosts} != the services' addresses {address}")
        if svc.get("command", [None])[0] not in ("cell", "edge", "dashboard"):
            errors.append(f"{name}: command {svc.get('command')} is not a service of the image")
    for net, cfg in (compose.get("networks") or {}).items():
        if not (cfg or {}).get("internal"):
            errors.append(f"network {net} is not internal")
    cell_volumes = services.get("cell", {}).get("volumes", [])
    if not any(v.split(":")[1] == "/var/lib/smc" and v.split(":")[0] in (compose.get("volumes") or {})
               for v in cell_volumes):
        errors.append("the cell's /var/lib/smc is not on a named volume")
    for e in errors:
        print(f"compose check: {e}", file=sys.stderr)
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
