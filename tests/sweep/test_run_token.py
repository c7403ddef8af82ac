"""The end of a sweep's run waits for the workers writing for it (dustoptics.sweep.run).

A run that fails (a full disk) cannot cancel its tasks already running on a cluster that
outlives it; one that had seen the run's token could write a chunk after the next run
began (found by ``scripts/fuzz.py --seed 2 --cases 200``: a full disk on a cluster of
threads, resumed at once, left a chunk whose marker no longer matched).
"""

from __future__ import annotations

import threading
import time

from dustoptics.sweep import run


def test_the_end_of_a_run_waits_for_its_writers_and_admits_none_after(tmp_path) -> None:
    store = tmp_path / "s.zarr"
    store.mkdir()
    token = run._RunToken(store)
    inside, leave, ended = threading.Event(), threading.Event(), threading.Event()
    seen: list[bool] = []

    def writer() -> None:
        with run._writing_for(store, token.name) as writes:
            seen.append(writes)
            inside.set()
            leave.wait(30)

    def end() -> None:
        token.end()
        ended.set()

    first = threading.Thread(target=writer)
    first.start()
    assert inside.wait(30)
    ender = threading.Thread(target=end)
    ender.start()
    time.sleep(0.5)
    assert not ended.is_set(), "the run ended while a worker was writing for it"
    assert not token.path.exists()  # no other worker starts meanwhile
    leave.set()
    first.join(30)
    ender.join(30)
    assert ended.is_set() and seen == [True]
    with run._writing_for(store, token.name) as writes:
        assert writes is False


def test_a_worker_that_opened_the_token_before_the_end_does_not_write_after_it(
    tmp_path, monkeypatch
) -> None:
    store = tmp_path / "s.zarr"
    store.mkdir()
    token = run._RunToken(store)
    real_open = run.os.open
    opened, go_on = threading.Event(), threading.Event()

    def slow_open(path, flags, *args):  # the worker pauses between open and lock
        fd = real_open(path, flags, *args)
        if threading.current_thread().name == "worker":
            opened.set()
            go_on.wait(30)
        return fd

    monkeypatch.setattr(run.os, "open", slow_open)
    seen: list[bool] = []

    def writer() -> None:
        with run._writing_for(store, token.name) as writes:
            seen.append(writes)

    worker = threading.Thread(target=writer, name="worker")
    worker.start()
    assert opened.wait(30)
    token.end()  # the worker holds the file open but no lock yet
    go_on.set()
    worker.join(30)
    assert seen == [False]
