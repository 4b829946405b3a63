"""An exec: policy for the tests (tests/exec_images_test.cc): reads each line and its images as
docs/guide/your-policy.md says, keeps them in DUMP_DIR (lines.jsonl, and tT_NAME_LAYER.bin per
image), and answers the same action every step.

usage: wire_dump.py DUMP_DIR [MODE]
MODE: "ok" (default); "early" reads half of the first image, answers, and waits 5 s before it
reads on (the rest stays in the pipe, where fetchscope sees it); "die" reads 100 bytes of the
first image, then exits with status 3.
"""
import json
import os
import sys

dump, mode = sys.argv[1], (sys.argv[2] if len(sys.argv) > 2 else "ok")
os.makedirs(dump, exist_ok=True)
lines = open(os.path.join(dump, "lines.jsonl"), "ab")
stdin = sys.stdin.buffer
while True:
    line = stdin.readline()
    if not line:
        break
    lines.write(line)
    lines.flush()
    msg = json.loads(line)
    for i, image in enumerate(msg.get("images", [])):
        if mode == "early" and i == 0:
            stdin.read(image["bytes"] // 2)
            break
        if mode == "die" and i == 0:
            stdin.read(100)
            sys.exit(3)
        data = stdin.read(image["bytes"])
        name = f"t{msg['t']}_{image['name']}_{image['layer']}.bin"
        with open(os.path.join(dump, name), "wb") as f:
            f.write(data)
    print("0.5 -0.25 0.2 0", flush=True)
    if mode == "early":
        import time

        time.sleep(5)
