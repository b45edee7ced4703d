import os

os.environ.setdefault("MPLBACKEND", "Agg")

import pytest  # noqa: E402

from empact._compile import drop_stale_cache  # noqa: E402
from empact.params import default_params  # noqa: E402

# an edited kernel must not be tested through integrators compiled against its old version
drop_stale_cache()


@pytest.fixture(scope="session")
def params():
    return default_params()


@pytest.fixture(scope="session")
def cluster():
    """The suite's one local Dask cluster (2 worker processes), shared by the sweep tests
    that use an address: its scheduler's address."""
    import distributed  # the 'dask' extra: the Makefile installs it, so a missing one fails
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=":0", silence_logs=50) as c:
        yield c.scheduler_address


#: the figures the tests read from the full report (png and svg); the background build draws
#: only these (`report_build.py`): every section, table, claim and the page are written
REPORT_FIGURES = ("fig4_actuation_modes", "fig5_actuation_energy", "fig6_actuation_frf",
                  "fig8_driveline_modes", "fig8_driveline_energy", "fig9_root_locus_cb",
                  "slip_stability_map", "fig2_identified_plant", "fig14_rig_T_mp")


class _Report:
    """The suite's one full build of the report (`empact reproduce`), run in the background
    by `report_build.py` from the start of the session (it overlaps the rest of the suite)."""

    def __init__(self) -> None:
        import subprocess
        import sys
        import tempfile
        from pathlib import Path

        self.folder = Path(tempfile.mkdtemp(prefix="empact-full-report-"))
        self.out = self.folder / "full" / "rep"
        self.out.parent.mkdir()
        self.results = self.folder / "results.json"
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("report_build.py")), str(self.out),
             str(self.results), *REPORT_FIGURES],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def result(self, timeout: float = 900.0):
        """(the CLI result: exit_code and output, the report folder), once built."""
        import json
        from types import SimpleNamespace

        self.proc.wait(timeout=timeout)
        return SimpleNamespace(**json.loads(self.results.read_text())), self.out

    def close(self) -> None:
        import shutil

        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.folder, ignore_errors=True)


_REPORT: list = []


@pytest.fixture(scope="session")
def full_report():
    """The suite's one full build of the report (`empact reproduce`), shared by the tests of
    the command and of the claims: (the CLI result, the report folder).  Only the figures the
    tests read are drawn (`REPORT_FIGURES`)."""
    if not _REPORT:
        _REPORT.append(_Report())
    return _REPORT[0].result()


class _Tour:
    """The README tour, run in the background by `readme_tour.py` (started once)."""

    def __init__(self) -> None:
        import subprocess
        import sys
        import tempfile
        from pathlib import Path

        self.folder = Path(tempfile.mkdtemp(prefix="empact-readme-tour-"))
        self.results = self.folder.with_suffix(".json")
        (self.folder / "tour").mkdir()
        self.proc = subprocess.Popen(
            [sys.executable, str(Path(__file__).with_name("readme_tour.py")),
             str(self.folder / "tour"), str(self.results)],
            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)

    def result(self, timeout: float = 900.0):
        """(the records of the steps, the tour's folder), once the tour (and the docs' snippets
        after it) has finished."""
        import json

        self.proc.wait(timeout=timeout)
        return json.loads(self.results.read_text()), self.folder / "tour"

    def close(self) -> None:
        import shutil

        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()
        shutil.rmtree(self.folder, ignore_errors=True)
        self.results.unlink(missing_ok=True)


_TOUR: list = []


#: The fast tier (``make test-fast``, ``pytest -m "not slow"``) leaves out the tests marked
#: ``slow`` here (``make test`` and CI run every test).  Slow are: every test of these files
#: (the README tour, the full report, a real Ctrl-C, the built site) ...
SLOW_FILES = {"test_readme.py", "test_report.py", "test_interrupt.py", "test_docs_site.py"}
#: ... every test that uses one of these fixtures (the full report build, the README tour, a
#: Dask cluster) ...
SLOW_FIXTURES = {"full_report", "readme_tour", "cluster"}
#: ... and these, by file (every parametrization): the CLI in subprocesses or many commands in
#: process, import checks in fresh interpreters, frozen-law and closed-loop runs, H-infinity
#: designs, figures laid out; each took >= 0.75 s in a run of the fast tier on the shared
#: 2-core machine (about 0.3 s of CPU).  Any other test, a new one included, is fast: add a
#: new test here (or mark it ``@pytest.mark.slow``) when it needs more than that.
SLOW_TESTS = {
    "test_drive_cycle.py": ("test_cli_json_keys_and_bad_input",
                            "test_plot_draws_the_four_panels"),
    "test_dynamic_cycle.py": ("test_cli_dynamic_json_and_plot",
                              "test_cycle_monte_carlo_forked_equals_in_process"),
    "test_cli.py": (
        "test_bad_input_one_line_exit_2_nothing_written", "test_cli_plot",
        "test_cli_rootlocus_zeros_frf_map", "test_cli_simulate_linearize_nmp",
        "test_control_check_strict_gates_a_script",
        "test_control_simulate_strict_exits_1_on_a_missed_target",
        "test_estimate_matches_known_filter", "test_frf_json_and_plot",
        "test_identify_draws_its_figure_only_when_asked",
        "test_json_has_schema_and_units_for_every_quantity", "test_output_folder_never_clobbered",
        "test_reproduce_draws_vector_figures_on_request",
        "test_simulation_that_stops_early_writes_only_when_asked"),
    "test_control.py": (
        "test_disk_margin_agrees_with_python_control", "test_hinf_refuses_ill_posed_problems",
        "test_lpv_interpolation_error"),
    "test_deprecations.py": ("test_each_deprecated_name_warns_with_its_replacement_and_removal",),
    "test_docs.py": ("test_control_chapter_examples_run",
                     "test_entry_point_examples_run_as_doctests"),
    "test_experiments.py": ("test_identified_plant_matches_exact_linearisation",
                            "test_rig_without_friction_matches_linear_model"),
    "test_fuzz_options.py": ("test_hostile_option_values",
                             "test_the_fuzzer_reaches_every_option_and_both_outcomes"),
    "test_hinf_loop.py": (
        "test_the_search_sees_the_loop_control_check_sees",
        "test_gradient_equals_central_differences", "test_outside_the_box_or_unstable_is_infinite",
        "test_design_on_a_small_family_improves_and_is_deterministic",
        "test_bad_options_are_one_line", "test_a_schedule_without_the_loop_is_refused",
        "test_shipped_hinf_is_stable_with_margin_on_the_loop_that_runs",
        "test_regression_shipped_hinf_is_the_documented_design",
        "test_shipped_hinf_between_the_grid_points", "test_the_grid_peak_is_slycots_norm"),
    "test_identification.py": (
        "test_frf_input_noise_h1_biased_h2_unbiased", "test_frf_mimo_h1_recovers_both_columns",
        "test_realize_noisy_steps_order_and_poles", "test_realize_recovers_order_poles_and_frf"),
    "test_integrators.py": ("test_order_on_stiff_linear_problem",
                            "test_sampled_controller_runs_with_every_method"),
    "test_io.py": ("test_lazy_module_defers_the_import",),
    "test_layout.py": (
        "test_cli_start_up_imports_only_what_the_command_needs",
        "test_control_commands_do_not_import_scipy_signal",
        "test_figures_of_linear_analyses_and_records_load_no_model",
        "test_linearize_and_nmp_do_not_import_python_control",
        "test_no_function_level_imports_outside_the_cli", "test_no_import_circles",
        "test_the_kernel_stays_inside_nonlinear"),
    "test_linear.py": ("test_calibration_reproduces_shipped_defaults",),
    "test_loop.py": (
        "test_linear_prediction_matches_the_nonlinear_run_for_a_small_step",
        "test_loop_model_is_stable_where_the_run_settles",
        "test_plant_response_in_chunks_is_the_one_stack_solve",
        "test_regression_golden_closed_loop", "test_regression_golden_linear_preprocess",
        "test_regression_golden_monte_carlo", "test_saturated_step_recovers_without_windup",
        "test_shift_keeps_its_clamping", "test_smallest_slip_reserve_is_the_per_sample_search",
        "test_the_compiled_loop_is_the_python_loop", "test_the_compiled_sample_is_update"),
    "test_nonlinear.py": ("test_energy_conserved_undamped_locked_belt",
                          "test_power_balance_with_dissipation",
                          "test_trim_and_trim_grid_agree_point_by_point"),
    "test_montecarlo_verdicts.py": (
        "test_a_tight_target_is_missed_by_every_run_and_counted",
        "test_same_seed_gives_the_same_table_bitwise", "test_spread_variables_reach_the_run",
        "test_strict_exit_codes", "test_wide_spread_without_a_scenario_is_one_line_exit_2",
        "test_wide_spread_loads_on_every_ratio_and_varies_the_shape_at_all_three"),
    "test_plausibility.py": ("test_fuzzed_parameter_files",),
    "test_plotting.py": (
        "test_draws_into_given_axes_and_returns_artists",
        "test_log_tick_labels_are_plain_text_of_the_tick_values",
        "test_log_value_axes_over_four_decades_lose_minor_ticks",
        "test_save_lays_out_once_and_keeps_the_layout", "test_symbols_and_save"),
    "test_shift_law.py": ("test_creep_power_closes_the_balance",
                          "test_load_step_with_held_servos_moves_ratio_as_kappa_predicts"),
    "test_slip.py": ("test_sign_of_largest_real_part_follows_sign_of_the_traction_slope",),
    "test_speaking.py": ("test_the_closing_line_lists_every_file_written",
                         "test_new_commands_show_progress_and_quiet_silences_stderr",
                         "test_new_commands_give_a_unit_for_every_number"),
    "test_shards.py": ("test_a_sigkilled_study_resumes_bitwise",
                       "test_one_and_two_workers_and_a_resume_on_two_are_bitwise_equal",
                       "test_cli_resume_bad_input_one_line_exit_2"),
    "test_sweep.py": (
        "test_core_never_imports_dask", "test_failed_runs_are_recorded_with_their_reason",
        "test_montecarlo_cli_local_cluster_equals_serial", "test_montecarlo_closed_loop_cli",
        "test_plant_analysis_slowest_mode_is_the_slowest_resonance",
        "test_unreachable_scheduler_one_line_exit_2"),
    "test_tune.py": ("test_a_proportional_multiplier_in_the_schedule_is_the_same_loop",
                     "test_sensitivity_peaks_are_the_loop_at_a_time_sensitivity",
                     "test_shipped_pi_has_production_margins",
                     "test_tuner_improves_a_detuned_start_deterministically"),
    "test_traction_table.py": (
        "test_control_simulate_with_a_table_meets_its_targets",
        "test_design_hinf_from_the_cli_uses_the_api_default",
        "test_mu_max_of_random_many_peaked_tables",
        "test_the_cli_takes_a_table_from_the_parameter_file"),
    "test_units.py": ("test_control_simulate_gives_slips_as_fractions",
                      "test_every_csv_header_has_units_in_one_style"),
}

#: the test that runs last: every signature the session compiled is one `compile_all` loads
LAST = "test_the_session_compiled_nothing_compile_all_does_not"


def pytest_collection_modifyitems(session, config, items):
    """Mark the slow tests ``slow`` (by file, by fixture, by name: `SLOW_TESTS`; or marked
    so in their file; every other test, a new one included, is in the fast tier), then run
    the tests that read the full report last (stable order otherwise: the rest of the suite
    runs while the report builds in the background, instead of waiting for it) and `LAST`
    after them."""
    for item in items:
        listed = SLOW_TESTS.get(item.path.name, ())
        for name in listed:  # a renamed test must not drop silently into the fast tier
            if item.module is not None and not hasattr(item.module, name):
                raise pytest.UsageError(f"tests/conftest.py SLOW_TESTS names {name!r}, which "
                                        f"{item.path.name} no longer defines")
        if (item.path.name in SLOW_FILES or getattr(item, "originalname", "") in listed
                or SLOW_FIXTURES & set(getattr(item, "fixturenames", ()))):
            item.add_marker(pytest.mark.slow)
    # the check that the session compiled nothing `compile_all` does not runs after the rest
    items.sort(key=lambda item: (getattr(item, "originalname", "") == LAST,
                                 "full_report" in getattr(item, "fixturenames", ())))


def pytest_collection_finish(session):
    """Start the full report build and the README tour in the background as soon as the
    session knows it will run their tests (the rest of the suite overlaps them)."""
    if session.config.option.collectonly:
        return
    if any("full_report" in getattr(item, "fixturenames", ()) for item in session.items):
        _REPORT.append(_Report())
    if any(getattr(item, "originalname", "") == "test_the_readme_tour_runs_as_written"
           for item in session.items):
        _TOUR.append(_Tour())


def pytest_sessionfinish(session):
    while _TOUR:
        _TOUR.pop().close()
    while _REPORT:
        _REPORT.pop().close()


@pytest.fixture(scope="session")
def readme_tour():
    """The README tour running in the background (`readme_tour.py`)."""
    if not _TOUR:
        _TOUR.append(_Tour())
    return _TOUR[0]
