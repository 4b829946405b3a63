#!/usr/bin/env bash
# Rewrites the generated documentation from the built binary (the docs_generated test fails
# until they are current): the CLI reference, the man page and the bash completion.
#   tools/regen-docs.sh [FETCHSCOPE]     (default build/fetchscope)
set -euo pipefail
cd "$(dirname "$0")/.."
bin=${1:-build/fetchscope}
mkdir -p docs/reference docs/man docs/completion
"$bin" help --markdown >docs/reference/cli.md
"$bin" help --man >docs/man/fetchscope.1
"$bin" help --bash-completion >docs/completion/fetchscope.bash
echo "regen-docs: wrote docs/reference/cli.md, docs/man/fetchscope.1, docs/completion/fetchscope.bash"
