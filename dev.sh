#!/usr/bin/env bash
# manylights developer entry point: installs what is missing, then builds and runs.
#
#   ./dev.sh render [manylights render flags]   build (release) and render a frame
#   ./dev.sh test                               the whole test suite (what CI runs)
#   ./dev.sh view [manylights view flags]       build (release) and open the interactive viewer
#   ./dev.sh <any manylights subcommand>        e.g. ./dev.sh check, ./dev.sh devices
#
# Needs: rustup (stable toolchain). Installs through apt when it can (root or passwordless sudo):
# the Vulkan loader, Mesa's CPU driver lavapipe, the Khronos validation layers, spirv-tools, the
# X11 libraries the viewer's window loads at run time, and Xvfb (the viewer's test runs a real
# window on a virtual X server).
# The first build also installs the pinned nightly rust-gpu needs and compiles its backend once,
# against the spirv-tools installed here (cached in ~/.cache/rust-gpu). A cold `./dev.sh devices`
# took 878 CPU-seconds on 2 cores this way, 1478 when SPIRV-Tools is compiled too (README).
set -euo pipefail
cd "$(dirname "$0")"

PACKAGES=(libvulkan1 mesa-vulkan-drivers vulkan-validationlayers spirv-tools vulkan-tools
          libx11-6 libx11-xcb1 libxcursor1 libxrandr2 libxi6 libxkbcommon-x11-0 xvfb xauth)

die() { echo "dev.sh: $*" >&2; exit 1; }

ensure_rust() {
    if ! command -v cargo >/dev/null 2>&1; then
        [ -x "$HOME/.cargo/bin/cargo" ] && export PATH="$HOME/.cargo/bin:$PATH"
    fi
    command -v cargo >/dev/null 2>&1 || die "cargo not found: install rustup (https://rustup.rs), then run this again"
    command -v rustup >/dev/null 2>&1 || die "rustup not found: rust-gpu installs its pinned nightly through rustup (https://rustup.rs)"
}

ensure_packages() {
    command -v dpkg-query >/dev/null 2>&1 || {
        echo "dev.sh: not a Debian/Ubuntu system: make sure a Vulkan loader, a Vulkan driver (e.g. Mesa lavapipe), the Khronos validation layer and spirv-tools are installed" >&2
        return 0
    }
    local missing=()
    for p in "${PACKAGES[@]}"; do
        dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
    done
    [ ${#missing[@]} -eq 0 ] && return 0
    local sudo=""
    if [ "$(id -u)" -ne 0 ]; then
        if command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
            sudo="sudo"
        else
            die "missing packages: ${missing[*]}. Install them with: sudo apt-get install ${missing[*]}"
        fi
    fi
    echo "dev.sh: installing ${missing[*]}" >&2
    $sudo apt-get update -qq >&2 || die "apt-get update failed; install by hand: ${missing[*]}"
    DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2 \
        || die "apt-get install failed; install by hand: ${missing[*]}"
}

first_build_notice() {
    [ -f "${XDG_CACHE_HOME:-$HOME/.cache}/rust-gpu/codegen/0_11_0/librustc_codegen_spirv.so" ] \
        || echo "dev.sh: first build: installing the pinned nightly and compiling the rust-gpu backend (once; see the README's build note)" >&2
}

cmd="${1:-}"
[ -n "$cmd" ] || die "usage: ./dev.sh render [flags] | test | <manylights subcommand>"
ensure_rust
ensure_packages
first_build_notice
case "$cmd" in
    test)
        shift
        # Every GPU test opens the Khronos validation layer with synchronization validation and
        # fails on any message. Clippy must be clean too. (No doc-test targets: there are none.)
        # Sponza/bunny tests run when the shared assets are there (../shared/assets by default,
        # or MANYLIGHTS_ASSETS); then they are required, so a broken path fails instead of skipping.
        assets="${MANYLIGHTS_ASSETS:-$PWD/../shared/assets}"
        if [ -d "$assets/sponza" ]; then
            export MANYLIGHTS_ASSETS="$assets" MANYLIGHTS_REQUIRE_ASSETS=1
        else
            echo "note: no Sponza at $assets: the Sponza tests are skipped (set MANYLIGHTS_ASSETS)" >&2
        fi
        log=$(mktemp)
        set +e
        cargo test --workspace --lib --bins --tests "$@" 2>&1 | tee "$log"
        status=${PIPESTATUS[0]}
        set -e
        passed=$(grep -o '[0-9]* passed' "$log" | awk '{s += $1} END {print s + 0}')
        failed=$(grep -o '[0-9]* failed' "$log" | awk '{s += $1} END {print s + 0}')
        rm -f "$log"
        if [ "$status" -eq 0 ]; then
            if cargo clippy --version >/dev/null 2>&1 || rustup component add clippy >/dev/null 2>&1; then
                cargo clippy --workspace --all-targets -- -D warnings || status=$?
            else
                echo "dev.sh: clippy unavailable, lint skipped" >&2
            fi
        fi
        echo "$passed passed, $failed failed"
        exit "$status"
        ;;
    *)
        cargo build --release -p host
        exec "${CARGO_TARGET_DIR:-target}/release/manylights" "$@"
        ;;
esac
