#!/usr/bin/env bash
# CAvatar Edge installer for the board beside the carpet (64-bit Raspberry Pi OS or Debian
# bookworm, Python >= 3.11). Run it as root from a copy of the repository:
#
#   sudo deploy/install.sh                        # install, or update, from this repository
#   sudo deploy/install.sh path/to/cavatar_edge-0.1.0-py3-none-any.whl
#   sudo deploy/install.sh --no-viz               # without matplotlib (see below)
#
# Running it again is safe: it updates the package, the unit and the udev rule, and never
# touches an existing /etc/cavatar/cavatar.toml or /etc/cavatar/cavatar.env.
#
# What it does (docs/install-pi.md explains each step and its manual equivalent):
#   1. apt-get installs python3-venv and libusb-1.0-0 when they are missing;
#   2. creates the system user `cavatar` (no login, no home), member of dialout and plugdev;
#   3. creates the virtual environment /opt/cavatar/venv and pip-installs the package into it
#      with its runtime dependencies (numpy, scipy, onnxruntime, pyserial, pyusb, smbus2,
#      paho-mqtt) and the viz extra (matplotlib: `cavatar calibrate` draws its report with it).
#      Never the export extra: torch is not needed on the board;
#   4. links /usr/local/bin/cavatar to /opt/cavatar/venv/bin/cavatar;
#   5. copies deploy/cavatar.example.toml to /etc/cavatar/cavatar.toml (only when that file does
#      not exist; always to /etc/cavatar/cavatar.example.toml for reference) and creates
#      /etc/cavatar/cavatar.env (mode 600) for CAVATAR_MQTT_PASSWORD;
#   6. creates /var/lib/cavatar (owned by cavatar), installs the unit and the udev rule, reloads
#      udev and systemd, restarts the service if it was running;
#   7. prints the next steps (calibrate, doctor, enable).

set -euo pipefail

PREFIX=/opt/cavatar
VENV=$PREFIX/venv
CONF_DIR=/etc/cavatar
STATE_DIR=/var/lib/cavatar
UNIT=/etc/systemd/system/cavatar.service
RULES=/etc/udev/rules.d/99-cavatar.rules
LINK=/usr/local/bin/cavatar
SERVICE_USER=cavatar
PYTHON=${PYTHON:-python3}

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
repo=$(dirname "$here")

say() { printf 'install.sh: %s\n' "$*"; }
warn() { printf 'install.sh: warning: %s\n' "$*" >&2; }
die() {
    printf 'install.sh: error: %s\n' "$*" >&2
    exit 1
}

usage() {
    sed -n '2,7p' "${BASH_SOURCE[0]}" | sed 's/^# \{0,1\}//'
}

# ----------------------------------------------------------------------------- arguments

extras="[viz]"
package=""
while [ $# -gt 0 ]; do
    case "$1" in
        -h | --help)
            usage
            exit 0
            ;;
        --no-viz)
            extras=""
            ;;
        -*)
            usage >&2
            die "unknown option $1"
            ;;
        *)
            [ -z "$package" ] || die "give one package (a repository folder or a .whl file), not several"
            package=$1
            ;;
    esac
    shift
done
package=${package:-$repo}

[ "$(id -u)" -eq 0 ] || die "run it as root: sudo $0"
for f in cavatar.service 99-cavatar.rules cavatar.example.toml; do
    [ -f "$here/$f" ] || die "$here/$f is missing; run install.sh from a complete copy of the repository"
done

# ----------------------------------------------------------------------------- 1. the system

arch=$(uname -m)
case "$arch" in
    aarch64 | arm64 | x86_64) ;;
    armv6l | armv7l | armhf)
        die "this is a 32-bit ARM system ($arch): onnxruntime publishes no wheels for it. Install the 64-bit Raspberry Pi OS (Raspberry Pi 3, 4 or 5) and run install.sh again"
        ;;
    *)
        warn "untested architecture $arch: pip must find onnxruntime, numpy and scipy wheels for it"
        ;;
esac

if command -v apt-get >/dev/null 2>&1; then
    missing=()
    for pkg in python3-venv libusb-1.0-0; do
        if ! dpkg-query -W -f='${Status}' "$pkg" 2>/dev/null | grep -q 'install ok installed'; then
            missing+=("$pkg")
        fi
    done
    if [ ${#missing[@]} -gt 0 ]; then
        say "installing ${missing[*]} (apt-get)"
        apt-get update -qq
        DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}"
    fi
else
    warn "no apt-get: make sure Python's venv module and libusb-1.0 are installed"
fi

command -v "$PYTHON" >/dev/null 2>&1 || die "no $PYTHON; install Python 3.11 or newer (or set PYTHON=/path/to/python3.11)"
"$PYTHON" -c 'import sys; sys.exit(sys.version_info < (3, 11))' ||
    die "$PYTHON is $("$PYTHON" -V 2>&1); CAvatar Edge needs Python 3.11 or newer (Debian bookworm has 3.11; or set PYTHON=)"

# ----------------------------------------------------------------------------- 2. the service user

for group in dialout plugdev; do
    getent group "$group" >/dev/null || groupadd --system "$group"
done
if id -u "$SERVICE_USER" >/dev/null 2>&1; then
    say "user $SERVICE_USER exists"
else
    useradd --system --user-group --home-dir "$STATE_DIR" --no-create-home \
        --shell /usr/sbin/nologin --comment "CAvatar Edge runtime" "$SERVICE_USER"
    say "created the system user $SERVICE_USER"
fi
usermod --append --groups dialout,plugdev "$SERVICE_USER"

# ----------------------------------------------------------------------------- 3. the package

if [ -x "$VENV/bin/python" ] && ! "$VENV/bin/python" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null; then
    die "$VENV holds an older Python; remove it (rm -rf $VENV) and run install.sh again"
fi
if [ ! -x "$VENV/bin/python" ]; then
    install -d -m 0755 "$PREFIX"
    "$PYTHON" -m venv "$VENV"
    say "created $VENV"
fi
pip=("$VENV/bin/python" -m pip --disable-pip-version-check)
"${pip[@]}" install --quiet --upgrade pip

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
if [ -f "$package" ] && [[ "$package" == *.whl ]]; then
    wheel=$package
elif [ -f "$package/setup.cfg" ] && [ -d "$package/edge" ]; then
    # Build from a clean copy, so root leaves no build/ or *.egg-info in your checkout.
    mkdir "$work/src" "$work/dist"
    tar -C "$package" --exclude=./.git --exclude=./.venv --exclude=./out --exclude=./build \
        --exclude='*.egg-info' --exclude=__pycache__ -cf - . | tar -C "$work/src" -xf -
    say "building the package from $package"
    if ! "${pip[@]}" wheel --no-deps --wheel-dir "$work/dist" "$work/src" >"$work/build.log" 2>&1; then
        cat "$work/build.log" >&2
        die "building the package failed (output above)"
    fi
    wheels=("$work"/dist/cavatar_edge-*.whl)
    [ -f "${wheels[0]}" ] || die "building $package made no cavatar_edge wheel"
    wheel=${wheels[0]}
else
    die "$package is neither a CAvatar Edge repository (setup.cfg, edge/) nor a .whl file"
fi
say "installing $(basename "$wheel")${extras} into $VENV (no torch: the export extra stays off the board)"
"${pip[@]}" install --quiet "${wheel}${extras}"
# The new code even when the version number did not change (an update from a newer checkout).
"${pip[@]}" install --quiet --no-deps --force-reinstall "$wheel"
if "$VENV/bin/python" -c 'import importlib.util, sys; sys.exit(importlib.util.find_spec("torch") is None)'; then
    warn "torch is installed in $VENV; the runtime never uses it (remove it: $VENV/bin/pip uninstall torch)"
fi
say "installed $("$VENV/bin/cavatar" --version)"

if [ -L "$LINK" ] || [ ! -e "$LINK" ]; then
    ln -sfn "$VENV/bin/cavatar" "$LINK"
else
    warn "$LINK exists and is not our link; left alone (the installed command is $VENV/bin/cavatar)"
fi

# ----------------------------------------------------------------------------- 4. configuration

install -d -m 0755 "$CONF_DIR"
install -m 0644 "$here/cavatar.example.toml" "$CONF_DIR/cavatar.example.toml"
if [ -e "$CONF_DIR/cavatar.toml" ]; then
    say "kept your $CONF_DIR/cavatar.toml (the current example is $CONF_DIR/cavatar.example.toml)"
else
    install -m 0644 "$here/cavatar.example.toml" "$CONF_DIR/cavatar.toml"
    say "wrote $CONF_DIR/cavatar.toml from the example: edit it before starting the service"
fi
if [ ! -e "$CONF_DIR/cavatar.env" ]; then
    (
        umask 077
        cat >"$CONF_DIR/cavatar.env" <<'EOF'
# Environment of the cavatar service (systemd EnvironmentFile=; root only, mode 600).
# The MQTT broker password of the user named in the mqtt:// sink URL; never put it in cavatar.toml.
#CAVATAR_MQTT_PASSWORD=
EOF
    )
    say "wrote $CONF_DIR/cavatar.env (mode 600): put CAVATAR_MQTT_PASSWORD there if the broker needs one"
fi
chown root:root "$CONF_DIR/cavatar.env"
chmod 0600 "$CONF_DIR/cavatar.env"

# systemd creates and owns it at each start (StateDirectory=); created now so that a calibration
# file can be put there before the first start.
install -d -m 0750 -o "$SERVICE_USER" -g "$SERVICE_USER" "$STATE_DIR"

# ----------------------------------------------------------------------------- 5. udev and systemd

install -D -m 0644 "$here/99-cavatar.rules" "$RULES"
if command -v udevadm >/dev/null 2>&1 && udevadm control --reload-rules 2>/dev/null; then
    udevadm trigger --action=add --subsystem-match=tty --subsystem-match=usb || true
    say "installed $RULES and reloaded udev: a plugged-in board appears as /dev/cavatar-carpet"
else
    warn "installed $RULES but could not reload udev (no udevd here?); unplug and plug the board, or reboot"
fi

install -D -m 0644 "$here/cavatar.service" "$UNIT"
if [ -d /run/systemd/system ]; then
    systemctl daemon-reload
    if systemctl is-active --quiet cavatar; then
        systemctl restart cavatar
        say "restarted the running cavatar service on the new version"
    fi
    say "installed $UNIT"
else
    warn "installed $UNIT, but systemd is not running here: start \`$VENV/bin/cavatar run --config $CONF_DIR/cavatar.toml\` some other way"
fi

# ----------------------------------------------------------------------------- 6. next steps

cat <<EOF

Installed. Next steps (docs/install-pi.md explains each):
  1. Find the board:        cavatar devices
  2. Calibrate the carpet (the service stopped, as your login user, in a folder of yours):
                            cavatar calibrate --source serial:///dev/cavatar-carpet --mass KG --out calibration.npz
                            sudo install -o $SERVICE_USER -g $SERVICE_USER -m 0640 calibration.npz $STATE_DIR/calibration.npz
  3. Edit the configuration: sudoedit $CONF_DIR/cavatar.toml   (and $CONF_DIR/cavatar.env for the MQTT password)
                            cavatar config validate $CONF_DIR/cavatar.toml
  4. Check everything, as the service would run:
                            sudo systemd-run --uid=$SERVICE_USER --pty --wait --collect --working-directory=$STATE_DIR -p EnvironmentFile=-$CONF_DIR/cavatar.env $VENV/bin/cavatar doctor --config $CONF_DIR/cavatar.toml
  5. Start it now and at every boot:
                            sudo systemctl enable --now cavatar
                            journalctl -u cavatar -f
                            cavatar status --config $CONF_DIR/cavatar.toml
EOF
