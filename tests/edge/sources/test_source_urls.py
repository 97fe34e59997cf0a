"""Source URLs: bad input gets an error that names the problem and shows the accepted form."""

import pytest

from edge.sources import SourceError, open_link, open_source


def test_unknown_scheme_lists_every_accepted_form():
    with pytest.raises(ValueError) as err:
        open_link("tcp://10.0.0.1:9000")
    msg = str(err.value)
    for form in ("serial:///dev/ttyACM0", "usb://", "replay://capture.bin", "sim://?people"):
        assert form in msg


def test_no_scheme_at_all():
    with pytest.raises(ValueError, match="Accepted forms"):
        open_link("/dev/ttyACM0")


def test_unknown_option_names_it_and_the_form():
    with pytest.raises(ValueError, match=r"no option 'baudrate'.*serial:///dev/ttyACM0\?baud="):
        open_link("serial:///dev/ttyACM0?baudrate=9600")


def test_malformed_option_value():
    with pytest.raises(ValueError, match="people=.*not valid"):
        open_link("sim://?people=many")
    with pytest.raises(ValueError, match="people must be 0..3"):
        open_link("sim://?people=9")
    with pytest.raises(ValueError, match="VID:PID in hex"):
        open_link("usb://carpet")


def test_missing_serial_port_lists_the_ports_that_exist(tmp_path, monkeypatch):
    import edge.sources.serial_port as sp

    monkeypatch.setattr(sp, "available_ports", lambda: ["/dev/ttyUSB7", "/dev/ttyACM3"])
    source = open_source(f"serial://{tmp_path}/ttyNOPE")
    with pytest.raises(SourceError) as err:
        source.start()
    msg = str(err.value)
    assert f"{tmp_path}/ttyNOPE does not exist" in msg
    assert "/dev/ttyUSB7, /dev/ttyACM3" in msg and "cavatar devices" in msg


def test_missing_replay_file_says_how_to_make_one(tmp_path):
    with pytest.raises(SourceError, match="cavatar record"):
        open_source(f"replay://{tmp_path}/none.bin").start()


def test_replay_of_a_file_that_is_not_a_capture(tmp_path):
    junk = tmp_path / "junk.bin"
    junk.write_bytes(bytes(range(256)) * 40)
    with pytest.raises(SourceError, match="no INFO packet"):
        open_source(f"replay://{junk}").start()
