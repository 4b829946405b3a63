#!/usr/bin/env python3
"""The documentation checks (ctest runs them, see tests/CMakeLists.txt; so does tools/test.sh).

  docs_check.py links ROOT [--ignore PAGE ...]   every relative link and #anchor in README.md
                                                 and docs/**/*.md resolves (GitHub's slugs);
                                                 README.md has at most 250 lines
  docs_check.py generated FETCHSCOPE ROOT        docs/reference/cli.md, docs/man/fetchscope.1 and
                                                 docs/completion/fetchscope.bash are what the
                                                 binary generates (tools/regen-docs.sh)
  docs_check.py completion FETCHSCOPE ROOT       the bash completion completes commands, options
                                                 and values
  docs_check.py runnable FETCHSCOPE ROOT [PAGE]  every ```sh block right after a
                                                 `<!-- runnable -->` line runs and exits 0:
                                                 README.md's, then every guide's in the order
                                                 docs/README.md lists them, all in one temporary
                                                 folder outside the checkout, with FETCHSCOPE's
                                                 folder first on PATH and MINARI_DATASETS_PATH
                                                 inside the folder; `<!-- output: TEXT -->`
                                                 lines after a block must appear in its output
"""
import difflib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import unicodedata

GENERATED = [
    ("docs/reference/cli.md", "--markdown"),
    ("docs/man/fetchscope.1", "--man"),
    ("docs/completion/fetchscope.bash", "--bash-completion"),
]


def pages(root):
    found = [os.path.join(root, "README.md")]
    for folder, _, files in os.walk(os.path.join(root, "docs")):
        found += [os.path.join(folder, f) for f in sorted(files) if f.endswith(".md")]
    return sorted(found)


def strip_code(text):
    """The text without fenced blocks and inline code (links there are not links)."""
    out, fence = [], None
    for line in text.split("\n"):
        m = re.match(r"^\s*(```+|~~~+)", line)
        if m:
            if fence is None:
                fence = m.group(1)[0] * 3
            elif line.strip().startswith(fence):
                fence = None
            out.append("")
            continue
        out.append("" if fence else line)
    return "\n".join(out)


def slug(heading):
    """GitHub's anchor for a heading: lowercased, punctuation dropped, spaces to hyphens."""
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", heading)  # links keep their text
    text = re.sub(r"<[^>]+>", "", text).strip().lower()
    kept = []
    for ch in text:
        cat = unicodedata.category(ch)
        if ch in "-_" or cat[0] in "LN" or cat == "Mn":
            kept.append(ch)
        elif ch == " ":
            kept.append("-")
    return "".join(kept)


def anchors(path):
    result, counts = set(), {}
    with open(path, encoding="utf-8") as f:
        text = strip_code(f.read())
    for line in text.split("\n"):
        m = re.match(r"^(#{1,6})\s+(.*?)\s*#*\s*$", line)
        if not m:
            continue
        base = slug(m.group(2))
        n = counts.get(base, 0)
        counts[base] = n + 1
        result.add(base if n == 0 else f"{base}-{n}")
    for m in re.finditer(r'<a\s+(?:name|id)="([^"]+)"', text):
        result.add(m.group(1))
    return result


def check_links(root, ignore):
    ignore = {os.path.normpath(os.path.join(root, p)) for p in ignore}
    problems, checked = [], 0
    cache = {}
    for page in pages(root):
        with open(page, encoding="utf-8") as f:
            text = strip_code(f.read())
        for lineno, line in enumerate(text.split("\n"), 1):
            for m in re.finditer(r"!?\[(?:[^\[\]]|\[[^\]]*\])*\]\(([^)\s]+)(?:\s+\"[^\"]*\")?\)", line):
                target = m.group(1)
                if re.match(r"^[a-z][a-z0-9+.-]*:", target):  # http:, https:, mailto:
                    continue
                checked += 1
                where = f"{os.path.relpath(page, root)}:{lineno}: link '{target}'"
                path, _, anchor = target.partition("#")
                dest = os.path.normpath(os.path.join(os.path.dirname(page), path)) if path else page
                if dest in ignore:
                    continue
                if not os.path.exists(dest):
                    problems.append(f"{where}: {os.path.relpath(dest, root)} does not exist")
                    continue
                if anchor and dest.endswith(".md"):
                    if dest not in cache:
                        cache[dest] = anchors(dest)
                    if anchor not in cache[dest]:
                        near = difflib.get_close_matches(anchor, sorted(cache[dest]), 1)
                        hint = f" (did you mean '#{near[0]}'?)" if near else ""
                        problems.append(f"{where}: no heading with anchor '#{anchor}' in "
                                        f"{os.path.relpath(dest, root)}{hint}")
    readme_lines = open(os.path.join(root, "README.md"), encoding="utf-8").read().count("\n")
    if readme_lines > 250:
        problems.append(f"README.md: {readme_lines} lines; it stays at 250 or fewer (move the "
                        "details into docs/guide or docs/reference and link to them)")
    for p in problems:
        print(p)
    print(f"README.md: {readme_lines} lines (at most 250)")
    print(f"links: {checked} relative links in {len(pages(root))} pages, {len(problems)} broken")
    return 1 if problems else 0


def check_generated(binary, root):
    failed = 0
    # `help COMMAND` is the command's --help; the generators take no COMMAND
    for words in (["record"], ["golden", "check"]):
        a = subprocess.run([binary, "help"] + words, capture_output=True, text=True)
        b = subprocess.run([binary] + words + ["--help"], capture_output=True, text=True)
        if a.returncode != 0 or a.stdout != b.stdout or not a.stdout:
            print(f"fetchscope help {' '.join(words)} (exit {a.returncode}) differs from "
                  f"fetchscope {' '.join(words)} --help:\n{a.stdout}{a.stderr}")
            failed = 1
    # every option that `COMMAND --help` lists is in the committed reference, in its section
    reference = open(os.path.join(root, "docs/reference/cli.md"), encoding="utf-8").read()
    commands = re.findall(r"^\| \[`([a-z -]+)`\]\(#", reference, re.M)
    for command in commands:
        section = reference.split(f"\n## {command}\n", 1)[-1].split("\n## ", 1)[0]
        listed = subprocess.run([binary] + command.split() + ["--help"], capture_output=True,
                                text=True).stdout
        for option in re.findall(r"^\s+(--[a-z0-9-]+)", listed, re.M):
            if f"{option} " not in section and f"{option}`" not in section:
                print(f"docs/reference/cli.md: `{command}`'s option {option} is missing")
                failed = 1
    print(f"cli.md: the options of {len(commands)} commands checked against their --help")
    bad = subprocess.run([binary, "help", "--markdown", "record"], capture_output=True, text=True)
    if bad.returncode != 2:
        print(f"fetchscope help --markdown record: exit {bad.returncode}, expected 2")
        failed = 1
    for rel, flag in GENERATED:
        out = subprocess.run([binary, "help", flag], capture_output=True, text=True)
        if out.returncode != 0:
            print(f"{binary} help {flag} failed ({out.returncode}): {out.stderr}")
            failed = 1
            continue
        path = os.path.join(root, rel)
        committed = open(path, encoding="utf-8").read() if os.path.exists(path) else ""
        if committed != out.stdout:
            diff = difflib.unified_diff(committed.splitlines(), out.stdout.splitlines(),
                                        rel + " (committed)", f"fetchscope help {flag}", lineterm="")
            print("\n".join(list(diff)[:40]))
            print(f"{rel} is not what `fetchscope help {flag}` prints: regenerate it with "
                  f"tools/regen-docs.sh (after building build/fetchscope) and commit it")
            failed = 1
        else:
            print(f"{rel}: current")
    return failed


def check_completion(binary, root):
    script = subprocess.run([binary, "help", "--bash-completion"], capture_output=True,
                            text=True, check=True).stdout
    # words typed (the last one is being completed), words that must be offered, and words that
    # must not be (the folder holds a file "notes.txt", a folder "runs", and a datasets root)
    cases = [
        (["rec"], {"record"}, set()),
        (["record", "--env-id", "FetchPu"], {"FetchPush-v4", "FetchPushDense-v4"}, set()),
        (["record", "--cam"], {"--camera"}, set()),
        (["record", "--camera", "ext"], {"external_camera_0"}, set()),
        (["record", "--camera", "tr"], {"track"}, set()),
        (["record", "--camera", "default,tr"], {"default,track"}, set()),
        (["render", "--overlay", "goal,hu"], {"goal,hud"}, set()),
        (["record", "--overlay", "cont"], {"contacts"}, set()),
        (["record", "--format", "mp4,we"], {"mp4,webm"}, set()),
        (["rollout", "--policy", "s"], {"scripted"}, set()),
        (["render", "--layers", "d"], {"depth"}, set()),
        (["golden", ""], {"check", "update"}, {"notes.txt", "runs"}),
        (["golden", "check", "--only"], {"--only"}, set()),
        (["help", "prob"], {"probe-actions"}, set()),
        (["help", ""], {"record"}, {"notes.txt", "runs"}),
        (["list-gpus", "--"], {"--gpu", "--json", "--help"}, set()),
        (["record", "--out", ""], {"runs"}, {"notes.txt"}),
        (["record", "--from", "fetchscope/"], {"fetchscope/FetchPush/scripted-v0"}, set()),
        (["report", ""], {"runs", "notes.txt"}, set()),
    ]
    failed = 0
    with tempfile.TemporaryDirectory(prefix="fetchscope-completion-") as cwd:
        open(os.path.join(cwd, "notes.txt"), "w").close()
        os.makedirs(os.path.join(cwd, "runs"))
        datasets = os.path.join(cwd, "runs", "datasets")
        os.makedirs(os.path.join(datasets, "fetchscope", "FetchPush", "scripted-v0", "data"))
        open(os.path.join(datasets, "fetchscope", "FetchPush", "scripted-v0", "data",
                          "metadata.json"), "w").close()
        env = dict(os.environ, MINARI_DATASETS_PATH=datasets)
        for words, expected, unwanted in cases:
            words = ["fetchscope"] + words
            program = script + (
                "COMP_WORDS=(" + " ".join("'" + w + "'" for w in words) + ")\n"
                f"COMP_CWORD={len(words) - 1}\n_fetchscope\nprintf '%s\\n' \"${{COMPREPLY[@]}}\"\n")
            out = subprocess.run(["bash", "-c", program], capture_output=True, text=True,
                                 cwd=cwd, env=env)
            offered = set(out.stdout.split())
            if out.returncode != 0 or not expected <= offered or offered & unwanted:
                print(f"completing {' '.join(words)!r}: expected {sorted(expected)}"
                      f"{' and none of ' + str(sorted(unwanted)) if unwanted else ''}, "
                      f"offered {sorted(offered)} {out.stderr}")
                failed = 1
    print(f"completion: {len(cases)} cases, {'FAILED' if failed else 'ok'}")
    return failed


def runnable_blocks(page):
    lines = open(page, encoding="utf-8").read().split("\n")
    blocks = []
    for i, line in enumerate(lines):
        if line.strip() == "<!-- runnable -->" and i + 1 < len(lines) and \
                lines[i + 1].strip() == "```sh":
            end = next(j for j in range(i + 2, len(lines)) if lines[j].strip() == "```")
            blocks.append((i + 2, "\n".join(lines[i + 2:end])))
    return blocks


def guide_order(root):
    """README.md, then the guides in the order docs/README.md lists them (any it does not list
    after, by name): the order a reader follows them in."""
    guide = os.path.join(root, "docs", "guide")
    listed = re.findall(r"\(guide/([\w-]+\.md)\)", open(os.path.join(root, "docs", "README.md"),
                                                         encoding="utf-8").read())
    names = []
    for name in listed + sorted(os.listdir(guide)):
        if name.endswith(".md") and name not in names and os.path.exists(os.path.join(guide, name)):
            names.append(name)
    return [os.path.join(root, "README.md")] + [os.path.join(guide, n) for n in names]


def check_runnable(binary, root, only):
    targets = guide_order(root)
    if only:
        targets = [t for t in targets if os.path.basename(t) in only]
    env = dict(os.environ)
    path = [os.path.dirname(os.path.abspath(binary))]
    # the guides' `python3` is Debian's, with python3-numpy: put one with numpy first on PATH
    numpy_python = next((p for p in (shutil.which("python3"), "/usr/bin/python3") if p and
                         subprocess.run([p, "-c", "import numpy"], capture_output=True).returncode
                         == 0), None)
    shim = tempfile.mkdtemp(prefix="fetchscope-docs-python-")
    if numpy_python:
        os.symlink(numpy_python, os.path.join(shim, "python3"))
        path.append(shim)
    env["PATH"] = os.pathsep.join(path + [env.get("PATH", "")])
    failed, count = 0, 0
    # one folder outside the checkout for every page, in order, as a reader follows them: a page
    # that makes what another already made is refused there, and nothing of the checkout
    # (examples/, golden/) is at hand: the binary finds what it installs beside itself
    with tempfile.TemporaryDirectory(prefix="fetchscope-docs-") as tmp:
        # datasets go into the folder, not the test machine's ~/.minari/datasets
        env["MINARI_DATASETS_PATH"] = os.path.join(tmp, "minari-datasets")
        for page in targets:
            for lineno, block in runnable_blocks(page):
                count += 1
                where = f"{os.path.relpath(page, root)}:{lineno}"
                start = time.monotonic()
                out = subprocess.run(["bash", "-euo", "pipefail", "-c", block], cwd=tmp, env=env,
                                     capture_output=True, text=True, timeout=300)
                seconds = time.monotonic() - start
                if out.returncode != 0:
                    print(f"{where}: exit {out.returncode} after {seconds:.1f} s:\n{block}\n"
                          f"--- stdout\n{out.stdout[-3000:]}\n--- stderr\n{out.stderr[-3000:]}")
                    failed = 1
                else:
                    print(f"{where}: ok ({seconds:.1f} s)")
                failed |= check_quoted_output(where, block, out.stdout + out.stderr, page, lineno)
    shutil.rmtree(shim, ignore_errors=True)
    print(f"runnable: {count} blocks, {'FAILED' if failed else 'ok'}")
    return failed if count else 1


def check_quoted_output(where, block, output, page, lineno):
    """A runnable block may be followed, after its closing fence, by a comment line
    `<!-- output: TEXT -->` for each number or line the page quotes from it: TEXT must appear in
    what the block printed, so the guide's numbers are the program's."""
    lines = open(page, encoding="utf-8").read().split("\n")
    end = next(j for j in range(lineno, len(lines)) if lines[j].strip() == "```")
    failed = 0
    for line in lines[end + 1:]:
        m = re.match(r"\s*<!-- output: (.*) -->\s*$", line)
        if not m:
            break
        if m.group(1) not in output:
            print(f"{where}: the page quotes '{m.group(1)}', which the block did not print")
            failed = 1
    return failed


def main(argv):
    if len(argv) < 3:
        print(__doc__)
        return 2
    mode = argv[1]
    if mode == "links":
        ignore = [argv[i + 1] for i, a in enumerate(argv) if a == "--ignore"]
        return check_links(argv[2], ignore)
    if mode == "generated":
        return check_generated(argv[2], argv[3])
    if mode == "completion":
        return check_completion(argv[2], argv[3])
    if mode == "runnable":
        return check_runnable(argv[2], argv[3], argv[4:])
    print(__doc__)
    return 2


if __name__ == "__main__":
    sys.exit(main(sys.argv))
