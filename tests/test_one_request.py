"""One request, one answer (issue 35): every cell of payload x population x heating x
question has its code in one registry, and a question asked through Python, the CLI and HTTP
gets one answer whose headline is the answer to the question asked (a batch's own time)."""

from __future__ import annotations

import json

import pytest
from api_support import asgi

from api.cli import main
from api.http import create_app
from dosing import Planner
from dosing.question import (
    Batch,
    Dose,
    Drug,
    Fluid,
    Heating,
    Jump,
    OneBead,
    Request,
    Schedule,
    plan,
)
from dosing.question.cells import CELLS

CASE = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 50.0}
# the batch under a ramp at 120 um: its smallest beads stay in the reduced model's region
RAMP_CASE = {**CASE, "dry_radius_um": 120.0}
RAMP = ["Heat to 308 K at 5 K/min"]
CV = {"kind": "lognormal", "cv": 0.2}
DRUG = {"diffusivity_cm2_s": 1e-6}


@pytest.mark.parametrize("key", sorted(CELLS))
def test_every_cell_resolves_its_request(key: tuple[str, ...]) -> None:
    """Each of the 16 cells takes its request (none is refused for want of code)."""
    payload = Drug(DRUG) if key[0] == "drug" else Fluid()
    population = Batch(CV) if key[1] == "batch" else OneBead()
    heating = Heating(RAMP) if key[2] == "protocol" else Jump(308.0)
    question = Schedule([0.3, 0.3], rests=[0.5]) if key[3] == "schedule" else Dose(0.5)
    req = Request(**CASE, heating=heating, question=question, payload=payload,
                  population=population)
    assert req.cell_key == key and req.planned is not None


# (name, request fields, CLI options, HTTP body): the cells answered without a full-solver run
CHEAP = [
    ("fluid one jump dose", dict(CASE, heating=Jump(308.0), question=Dose(0.8)),
     ["--t-end", "308", "--fraction", "0.8"], {"t_end": 308.0, "dose_fraction": 0.8}),
    ("fluid batch jump dose", dict(CASE, heating=Jump(308.0), question=Dose(0.8),
                                   population=Batch(CV)),
     ["--t-end", "308", "--fraction", "0.8", "--size-cv", "0.2"],
     {"t_end": 308.0, "dose_fraction": 0.8, "size_distribution": CV}),
    ("fluid one protocol dose", dict(CASE, heating=Heating(RAMP), question=Dose(0.8)),
     ["--protocol", RAMP[0], "--fraction", "0.8"], {"protocol": RAMP, "dose_fraction": 0.8}),
    ("fluid batch protocol dose", dict(RAMP_CASE, heating=Heating(RAMP), question=Dose(0.8),
                                       population=Batch(CV)),
     ["--protocol", RAMP[0], "--fraction", "0.8", "--size-cv", "0.2"],
     {"protocol": RAMP, "dose_fraction": 0.8, "size_distribution": CV}),
    ("drug one jump dose", dict(CASE, heating=Jump(308.0), question=Dose(0.8),
                                payload=Drug({"diffusivity_cm2_s": 0.0})),
     ["--t-end", "308", "--fraction", "0.8", "--drug-diffusivity-cm2-s", "0"],
     {"t_end": 308.0, "dose_fraction": 0.8, "drug": {"diffusivity_cm2_s": 0.0}}),
]



@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    from concurrent.futures import ThreadPoolExecutor

    p = Planner(cache_path=str(tmp_path_factory.mktemp("one") / "c.sqlite"),
                executor=ThreadPoolExecutor(2))
    yield p
    p.close()


@pytest.mark.anyio
@pytest.mark.parametrize("name,fields,cli,body", CHEAP, ids=[c[0] for c in CHEAP])
async def test_one_answer_whatever_the_way_in(name, fields, cli, body, planner, capsys,
                                              tmp_path) -> None:
    """Python, the CLI and HTTP give the same headline for the same question."""
    py = plan(Request(**fields), planner=planner)
    assert py.cell == name.replace(" ", " · ")
    one = fields.get("population", OneBead()).key == "one"
    assert (py.batch is None) == one
    if not one:  # the headline is the batch's own time, not its mean bead's
        assert py.seconds == py.batch.seconds and py.seconds > py.answer.seconds
        assert py.to_dict()["reference_bead"]["seconds"] == py.answer.seconds
    size = ["--dry-radius-um", str(fields["dry_radius_um"])]
    assert main(["dose", "--gel", "ANB", "--t-start", "302", *size, *cli, "--json",
                 "--cache", str(tmp_path / "c.sqlite")]) == 0
    out = json.loads(capsys.readouterr().out)
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        r = await raw.post("/v1/dose-time", json={"gel": "ANB", "t_start": 302.0,
                                                  "dry_radius_um": fields["dry_radius_um"],
                                                  **body})
    assert r.status_code == 200, r.text
    want = py.to_dict()
    check_envelope(want)
    check_views(py)
    for d in (out, r.json()):
        assert d["cell"] == py.cell and d["question"] == "dose"
        assert d["time"] == pytest.approx(py.time, rel=1e-12)
        assert d["seconds"] == pytest.approx(py.seconds, rel=1e-12)
        assert d["envelope_seconds"] == pytest.approx(want["envelope_seconds"], rel=1e-9)
        assert d["dominant_uncertainty"]["name"] == want["dominant_uncertainty"]["name"]
        assert d["request"]["population"]["kind"] == fields.get("population", OneBead()).key


@pytest.mark.anyio
async def test_a_schedule_reads_the_same_everywhere(planner, capsys, tmp_path) -> None:
    """The hold reading asked alone: the headline says it is the hold reading."""
    q = Schedule([0.3, 0.3, 0.3], rests=[0.5, 0.5], check_protocol=False, correct=False)
    py = plan(Request(**CASE, heating=Jump(308.0), question=q), planner=planner)
    assert py.reading == "hold" and len(py.actuation_seconds) == 3
    assert main(["schedule", "--gel", "ANB", "--t-start", "302", "--t-end", "308",
                 "--dry-radius-um", "50", "--doses", "0.3", "0.3", "0.3", "--rests", "0.5",
                 "0.5", "--no-check", "--no-correct", "--json",
                 "--cache", str(tmp_path / "c.sqlite")]) == 0
    out = json.loads(capsys.readouterr().out)
    async with asgi(create_app(planner=planner, warm=False)) as (_, raw):
        r = await raw.post("/v1/schedule", json={
            **CASE, "t_end": 308.0, "doses": [0.3, 0.3, 0.3], "rests": [0.5, 0.5],
            "check_protocol": False, "correct": False})
    assert r.status_code == 200, r.text
    for d in (out, r.json()):
        assert d["reading"] == "hold"
        assert d["actuation_seconds"] == pytest.approx(py.actuation_seconds, rel=1e-12)


def test_python_plan_dose_answers_a_batch() -> None:
    """A DoseRequest with a size_distribution is answered for the batch (it was the mean
    bead's time, without a word)."""
    from dosing import DoseRequest, plan_dose

    ans = plan_dose(DoseRequest(gel="ANB", t_start=302, t_end=308, dose_fraction=0.8,
                                dry_radius_um=50, size_distribution=CV))
    bead = plan_dose(DoseRequest(gel="ANB", t_start=302, t_end=308, dose_fraction=0.8,
                                 dry_radius_um=50))
    assert ans.seconds == ans.batch.seconds and ans.seconds > 1.1 * bead.seconds


def test_a_schedule_under_a_protocol_meets_every_dose(fake_planner) -> None:
    """Every heating follows the protocol (its staircase on the stand-in solver): the
    corrected times meet each dose, where the hold reading's times do not; its first
    heating is the protocol dose's own (one heating, nothing before it)."""
    q = Schedule([0.3, 0.3], rests=[0.5])
    ans = plan(Request(**CASE, heating=Heating(RAMP), question=q), planner=fake_planner)
    got = ans.corrected["delivered_fractions"]
    assert ans.reading == "corrected" and got == pytest.approx([0.3, 0.3], rel=0.01)
    assert abs(ans.protocol_check["delivered_fractions"][1] / 0.3 - 1.0) > 0.01
    assert "follows the protocol" in ans.note
    first = plan(Request(**CASE, heating=Heating(RAMP), question=Dose(0.3)),
                 planner=fake_planner)
    assert ans.actuation_times[0] == pytest.approx(first.time, rel=0.01)


def test_a_batch_schedule_under_a_protocol(fake_planner) -> None:
    """Each size runs the protocol in its own tau; a CV of 0 is the single bead's schedule
    exactly."""
    q = Schedule([0.3, 0.3], rests=[0.5])
    case = {**CASE, "dry_radius_um": 2.0}
    one = plan(Request(**case, heating=Heating(RAMP), question=q), planner=fake_planner)
    zero = plan(Request(**case, heating=Heating(RAMP), question=q,
                        population=Batch({"cv": 0.0})), planner=fake_planner)
    assert zero.actuation_times == one.actuation_times
    spread = plan(Request(**case, heating=Heating(RAMP), question=q,
                          population=Batch({"cv": 0.2})), planner=fake_planner)
    assert spread.cell == "fluid · batch · protocol · schedule"
    assert spread.corrected["delivered_fractions"] == pytest.approx([0.3, 0.3], rel=0.011)
    assert spread.actuation_times != one.actuation_times
    assert "follows the protocol" in spread.note


@pytest.fixture
def cli_on_fake(monkeypatch, fake_planner):
    """The CLI's one-shot planner on the fake solver."""
    import dosing.planner

    real = dosing.planner.one_shot
    monkeypatch.setattr(dosing.planner, "one_shot", lambda path, ex, **kw: real(
        path, ex, solver=fake_planner.solver, **kw))


FAKE_CASE = {"gel": "ANB", "t_start": 302.0, "dry_radius_um": 2.0}
# (name, heating, population, CLI options, HTTP fields): the fluid schedules, each a job
SCHEDULES = [
    ("fluid one jump schedule", Jump(308.0), OneBead(), ["--t-end", "308"], {"t_end": 308.0}),
    ("fluid one protocol schedule", Heating(RAMP), OneBead(), ["--protocol", RAMP[0]],
     {"protocol": RAMP}),
    ("fluid batch jump schedule", Jump(308.0), Batch({"cv": 0.2}),
     ["--t-end", "308", "--size-cv", "0.2"], {"t_end": 308.0, "size_distribution": {"cv": 0.2}}),
    ("fluid batch protocol schedule", Heating(RAMP), Batch({"cv": 0.2}),
     ["--protocol", RAMP[0], "--size-cv", "0.2"],
     {"protocol": RAMP, "size_distribution": {"cv": 0.2}}),
]


@pytest.mark.anyio
@pytest.mark.parametrize("name,heating,population,cli,body", SCHEDULES,
                         ids=[c[0] for c in SCHEDULES])
async def test_a_schedule_reads_the_same_whatever_the_way_in(
        name, heating, population, cli, body, fake_planner, cli_on_fake, capsys,
        tmp_path) -> None:
    """The corrected times lead, the same through Python, the CLI and HTTP (a job)."""

    q = Schedule([0.3, 0.3], rests=[0.5])
    py = plan(Request(**FAKE_CASE, heating=heating, question=q, population=population),
              planner=fake_planner)
    assert py.cell == name.replace(" ", " · ") and py.reading == "corrected"
    check_views(py)
    assert main(["schedule", "--gel", "ANB", "--t-start", "302", "--dry-radius-um", "2",
                 "--doses", "0.3", "0.3", "--rests", "0.5", *cli, "--json",
                 "--cache", str(tmp_path / "c.sqlite")]) == 0
    out = json.loads(capsys.readouterr().out)
    async with asgi(create_app(planner=fake_planner, warm=False)) as (api, raw):
        r = await raw.post("/v1/schedule", json={**FAKE_CASE, "doses": [0.3, 0.3],
                                                 "rests": [0.5], **body})
        assert r.status_code == 202, r.text
        v = await api.wait_validation(r.json()["validation_id"], timeout=120.0, interval=0.05)
    assert v.status == "done", v.error
    for d in (out, v.result):
        assert d["cell"] == py.cell and d["reading"] == "corrected"
        assert d["actuation_times"] == pytest.approx(py.actuation_times, rel=1e-12)


@pytest.mark.slow
def test_a_drug_batch_schedule_of_one_size_is_the_single_beads(planner) -> None:
    """The population seam lifted over one node (CV 0) is the single bead's drug schedule
    exactly; a spread delays it (real solver, a drug the fluid carries: D0 = 0)."""
    q = Schedule([0.3, 0.3], rests=[0.1])
    drug = Drug({"diffusivity_cm2_s": 0.0})
    one = plan(Request(**CASE, heating=Jump(308.0), question=q, payload=drug),
               planner=planner)
    zero = plan(Request(**CASE, heating=Jump(308.0), question=q, payload=drug,
                        population=Batch({"cv": 0.0})), planner=planner)
    assert zero.actuation_times == one.actuation_times
    assert zero.corrected["delivered_fractions"] == one.corrected["delivered_fractions"]
    spread = plan(Request(**CASE, heating=Jump(308.0), question=q, payload=drug,
                          population=Batch({"cv": 0.2})), planner=planner)
    assert spread.corrected["delivered_fractions"] == pytest.approx([0.3, 0.3], rel=0.01)
    assert all(s > o for s, o in zip(spread.actuation_times, one.actuation_times,
                                     strict=True))


def test_release_takes_the_step_grammar(capsys) -> None:
    """`thermogel release --protocol` takes the heating grammar as `dose` does (its 0.05 K
    staircase), and the tau pairs it took before; an until-step is refused naming it."""
    base = ["release", "--gel", "ANB", "--t-start", "302", "--dry-radius-um", "50",
            "--drug-diffusivity-cm2-s", "1e-6", "--samples", "50", "--json"]
    assert main([*base, "--protocol", "Heat to 308 K at 600 K/min; Hold at 308 K for 0.01 tau"
                 ]) == 0
    ramp = json.loads(capsys.readouterr().out)
    assert ramp["released_fraction"][-1] > 0.0 and ramp["timescale_seconds"] > 0.0
    assert main([*base, "--protocol", "Hold at 308 K until 30 % released"]) == 2
    assert "protocol[0].until" in capsys.readouterr().err
    assert main([*base, "--protocol", "0.01:308"]) == 0


TWO = {"kind": "table", "sizes_um": [45.0, 55.0]}
D0 = {"diffusivity_cm2_s": 0.0}  # a drug the fluid carries: the cheapest drug runs
# (name, heating, population, question, CLI options, HTTP fields): the drug cells
DRUG_CELLS = [
    ("drug one protocol dose", Heating(RAMP), OneBead(), Dose(0.5),
     ["dose", "--protocol", RAMP[0], "--fraction", "0.5"],
     {"protocol": RAMP, "dose_fraction": 0.5}),
    ("drug batch jump dose", Jump(308.0), Batch(CV), Dose(0.5),
     ["dose", "--t-end", "308", "--fraction", "0.5", "--size-cv", "0.2"],
     {"t_end": 308.0, "dose_fraction": 0.5, "size_distribution": CV}),
    ("drug one jump schedule", Jump(308.0), OneBead(), Schedule([0.3, 0.3], rests=[0.1]),
     ["schedule", "--t-end", "308", "--doses", "0.3", "0.3", "--rests", "0.1"],
     {"t_end": 308.0, "doses": [0.3, 0.3], "rests": [0.1]}),
    ("drug one protocol schedule", Heating(RAMP), OneBead(), Schedule([0.3, 0.3], rests=[0.1]),
     ["schedule", "--protocol", RAMP[0], "--doses", "0.3", "0.3", "--rests", "0.1"],
     {"protocol": RAMP, "doses": [0.3, 0.3], "rests": [0.1]}),
    ("drug batch jump schedule", Jump(308.0), Batch(CV), Schedule([0.3, 0.3], rests=[0.1]),
     ["schedule", "--t-end", "308", "--doses", "0.3", "0.3", "--rests", "0.1", "--size-cv",
      "0.2"], {"t_end": 308.0, "doses": [0.3, 0.3], "rests": [0.1], "size_distribution": CV}),
    ("drug batch protocol dose", Heating(RAMP), Batch(CV), Dose(0.5),
     ["dose", "--protocol", RAMP[0], "--fraction", "0.5", "--size-cv", "0.2"],
     {"protocol": RAMP, "dose_fraction": 0.5, "size_distribution": CV}),
    # a measured table of two sizes (exact, no second rule): the costliest cell, 47 s here
    ("drug batch protocol schedule", Heating(RAMP), Batch(TWO), Schedule([0.3]),
     ["schedule", "--protocol", RAMP[0], "--doses", "0.3", "--sizes", "{sizes}"],
     {"protocol": RAMP, "doses": [0.3], "size_distribution": TWO}),
]


def check_envelope(d: dict) -> None:
    """Issue 36: an answer's envelope holds its point, is no narrower than its largest
    counted part, and its parts are typed in one vocabulary."""
    names = {"numerical", "reduction", "interfacial_length", "front_law", "timescale", "mesh",
             "quadrature", "parameters"}
    parts = d["envelope"]["parts"]
    assert parts and set(parts) <= names and "front_law" in parts, parts
    for name, part in parts.items():
        assert part["low"] <= 1.0 <= part["high"] and part["how_to_pin"], name
        def given(x: dict) -> dict:  # a typed schema fills its optional fields with null
            return {k: v for k, v in x.items() if v is not None}

        assert given(d["uncertainty"][name]) == given(part)
    widest = max(p["factor"] for p in parts.values() if p["counted"])
    env = d["envelope_seconds"] if d["envelope_seconds"] is not None else d["envelope_time"]
    points = _headline(d) if d["envelope_seconds"] is None else (
        d["actuation_seconds"] if d["question"] == "schedule" else [d["seconds"]])
    for (lo, hi), x in zip(env if d["question"] == "schedule" else [env], points,
                           strict=True):
        assert lo <= x <= hi and hi / lo >= widest * (1 - 1e-9)
    assert d["dominant_uncertainty"]["how_to_pin"]


def check_views(res) -> None:
    """Every cell's one result has its notebook views, led by what it cannot rule out: the
    HTML opens with the envelope's lines (as the CLI's text answer), the dose's table row
    carries the envelope of its JSON, a schedule's table and Dataset are its events."""
    import html as html_module

    d = res.to_dict()
    view = res._repr_html_()
    lead = view.split("</p>", 1)[0]
    assert lead.startswith("<div><p>") and html_module.escape(
        res.envelope.lines("x")[0].split(" ", 1)[1]) in lead, lead
    df = res.to_dataframe()
    if d["question"] == "dose":
        assert len(df) == 1 and df["cell"][0] == res.cell
        low = df["envelope_low_s [s]"][0] if d["envelope_seconds"] else df["envelope_low [1]"][0]
        want = (d["envelope_seconds"] or d["envelope_time"])[0]
        assert low == pytest.approx(want, rel=1e-12)
        assert df["dominant_uncertainty"][0] == d["dominant_uncertainty"]["name"]
        assert list(df.columns[:3]) == ["cell", "envelope_low_s [s]", "envelope_high_s [s]"]
        assert df["seconds [s]"][0] == d["seconds"]  # the cell's own fields follow
    else:
        assert len(df) == len(d["events"]) and df.attrs["reading"] == res.reading
        ds = res.to_xarray()
        assert ds.sizes["step"] == len(d["events"]) and ds.attrs["headline"] == res.headline
        assert res.answer._repr_html_().startswith("<table")  # the cell's own answer too


def _headline(d: dict) -> list[float]:
    return d["actuation_times"] if d["question"] == "schedule" else [d["time"]]


@pytest.mark.slow
@pytest.mark.anyio
@pytest.mark.parametrize("name,heating,population,question,cli,body", DRUG_CELLS,
                         ids=[c[0] for c in DRUG_CELLS])
async def test_a_drug_cell_reads_the_same_whatever_the_way_in(
        name, heating, population, question, cli, body, capsys, tmp_path) -> None:
    """The drug cells on the real solver (a drug the fluid carries), through Python, the
    CLI and HTTP (a job) on one cache: one headline."""
    import asyncio
    from concurrent.futures import ThreadPoolExecutor

    cache = str(tmp_path / "drug.sqlite")
    sizes = tmp_path / "sizes.csv"
    sizes.write_text("radius_um\n45\n55\n")
    cli = [str(sizes) if c == "{sizes}" else c for c in cli]
    with Planner(cache_path=cache, executor=ThreadPoolExecutor(2)) as p:
        res = plan(Request(**CASE, heating=heating, question=question, payload=Drug(D0),
                           population=population), planner=p)
        check_views(res)
        py = res.to_dict()
        assert py["cell"] == name.replace(" ", " · ") and py["drug"] is True
        assert main([cli[0], "--gel", "ANB", "--t-start", "302", "--dry-radius-um", "50",
                     "--drug-diffusivity-cm2-s", "0", *cli[1:], "--json",
                     "--cache", cache]) == 0
        out = json.loads(capsys.readouterr().out)
        route = "/v1/schedule" if question.key == "schedule" else "/v1/dose-time"
        async with asgi(create_app(planner=p, warm=False)) as (api, raw):
            r = await raw.post(route, json={**CASE, "drug": D0, **body})
            assert r.status_code in (200, 202), r.text
            got = r.json()
            if r.status_code == 202:
                for _ in range(6000):
                    v = await api.validation(got["validation_id"])
                    if v.status in ("done", "failed"):
                        break
                    await asyncio.sleep(0.05)
                assert v.status == "done", v.error
                got = v.result
    check_envelope(py)
    for d in (out, got):
        assert d["cell"] == py["cell"]
        assert _headline(d) == pytest.approx(_headline(py), rel=1e-9)
        check_envelope(d)
