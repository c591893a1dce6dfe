"""Helpers for the benchmarks that drive a meshflow hub over HTTP (standard library only).

    python3 bench/hub_jobs.py run HUB WORKFLOW.xml MESH [--transfer smaller|output] > job.json
        submits a job (multipart, as `curl -F` would), waits for it to end, prints its status JSON.
"""
import json
import sys
import time
import urllib.request
import uuid


def get(url):
    with urllib.request.urlopen(url, timeout=60) as answer:
        return json.load(answer)


def submit(hub, workflow_xml, mesh_path, transfer="smaller"):
    boundary = uuid.uuid4().hex
    parts = []
    def field(name, value, filename=None):
        head = f'--{boundary}\r\nContent-Disposition: form-data; name="{name}"'
        if filename:
            head += f'; filename="{filename}"\r\nContent-Type: application/octet-stream'
        parts.append(head.encode() + b"\r\n\r\n" + value + b"\r\n")
    field("workflow", workflow_xml.encode())
    field("transfer", transfer.encode())
    with open(mesh_path, "rb") as f:
        field("input", f.read(), filename=mesh_path.rsplit("/", 1)[-1])
    body = b"".join(parts) + f"--{boundary}--\r\n".encode()
    request = urllib.request.Request(hub + "/api/jobs", data=body, method="POST",
                                     headers={"Content-Type": f"multipart/form-data; boundary={boundary}"})
    with urllib.request.urlopen(request, timeout=600) as answer:
        return json.load(answer)["id"]


def wait(hub, job_id, limit_s=3600, every_s=0.05):
    deadline = time.time() + limit_s
    while time.time() < deadline:
        job = get(f"{hub}/api/jobs/{job_id}")
        if job["state"] in ("done", "failed", "cancelled"):
            return job
        time.sleep(every_s)
    raise TimeoutError(f"job {job_id} did not end within {limit_s} s")


def run(hub, workflow_path, mesh_path, transfer="smaller"):
    with open(workflow_path) as f:
        xml = f.read()
    job = wait(hub, submit(hub, xml, mesh_path, transfer))
    if job["state"] != "done":
        raise RuntimeError(f"job {job['id']} {job['state']}: {job.get('error')}")
    return job


if __name__ == "__main__":
    if len(sys.argv) >= 5 and sys.argv[1] == "run":
        transfer = sys.argv[6] if len(sys.argv) > 6 and sys.argv[5] == "--transfer" else "smaller"
        print(json.dumps(run(sys.argv[2], sys.argv[3], sys.argv[4], transfer)))
    else:
        sys.exit(__doc__)
