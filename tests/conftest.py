from pathlib import Path

import pytest

DATA = Path(__file__).parent / "data"


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture(scope="session")
def repo_root() -> Path:
    return Path(__file__).resolve().parents[1]


# ------------------------------------------------------------------ markers (pyproject.toml lists them)
# Tests that start other programs carry what they start: `subprocess` (python processes: the CLI,
# rollout workers, pip), `ray` (a Ray instance or cluster), `browser` (headless Chromium), `vulkan`
# (a Vulkan device or lavapipe); each of these is `slow` too. `slow` alone marks in-process tests
# that simulate long. `pytest -m "not slow"` is the inner loop; `pytest` runs everything.
# MARKS: marker -> test file (or folder) -> its tests with that marker (empty: all of them; a
# parametrized test: every case). One table, so that each test file's text stays as it was.
ALL = ()
MARKS: dict[str, dict[str, tuple[str, ...]]] = {
    "subprocess": {
        "tests/evolve/cli/test_errors.py": ("test_an_internal_error_inside_a_command_shows_its_traceback",
                                            "test_debug_shows_the_traceback_of_bad_input_too",
                                            "test_an_error_in_a_users_task_module_shows_the_users_code"),
        "tests/evolve/rollout/test_pool.py": (
            "test_runs_give_the_same_results_with_one_or_two_worker_processes",
            "test_two_worker_processes_return_exactly_the_in_process_returns",
            "test_errors_in_a_worker_are_raised_in_the_caller_and_the_pool_survives",
            "test_a_worker_killed_mid_generation_is_started_again_with_the_same_results"),
        "tests/evolve/rollout/test_ray_cluster.py": ALL,
        "tests/evolve/rollout/test_robust.py": (
            "test_robust_runs_do_not_depend_on_the_worker_count_and_their_champion_rescores_exactly",
            "test_a_sigkilled_robust_run_resumes_in_a_new_process_on_two_workers_to_the_same_run",
            "test_with_reevaluate_elites_are_simulated_again_with_fresh_noise_and_the_run_stays_exact",
            "test_episode_noise_follows_the_episode_not_its_slot_in_the_batch_or_the_worker"),
        "tests/evolve/rollout/test_user_task.py": ALL,
        "tests/evolve/runs/test_checkpoint.py": (
            "test_a_pickle_planted_in_checkpoints_runs_nothing_and_the_run_resumes_from_the_newest_real_one",),
        "tests/evolve/runs/test_experiment.py": (
            "test_ctrl_c_writes_a_checkpoint_and_every_generation_number_agrees",),
        "tests/evolve/runs/test_final_selection.py": (
            "test_choosing_again_on_one_or_two_workers_changes_nothing",),
        "tests/evolve/runs/test_folder_trust.py": ALL,
        "tests/evolve/runs/test_imports.py": ALL,
        "tests/evolve/runs/test_ray_nodes.py": ALL,
        "tests/evolve/runs/test_resume.py": ("test_sigkilled_run_resumes_in_a_new_process_to_the_same_run",
                                             "test_no_usable_checkpoint_is_one_error_line"),
        "tests/evolve/runs/test_stops.py": ALL,
        "tests/evolve/runs/test_sweep.py": ("test_a_killed_sweep_resumes_to_the_same_runs",),
        "tests/evolve/runs/test_script_task.py": ALL,
        "tests/evolve/test_cli_precision.py": ALL,
        "tests/evolve/test_cli_backend.py": ALL,
        "tests/evolve/test_working_folder.py": (
            "test_every_readme_command_runs_beside_a_tasks_py_an_evolve_py_and_a_tsim_py",),
        "tests/evolve/test_cli_errors.py": ("test_config_that_is_a_list", "test_unknown_arch",
                                            "test_unavailable_arch_in_this_process",
                                            "test_unavailable_arch_in_rollout_workers",
                                            "test_a_closed_stdout_is_no_disk_error_and_the_run_goes_on"),
        "tests/sgr/evogym/test_viewer.py": ("test_screen_mode_opens_a_window_showing_the_frame_under_xvfb",),
        "tests/sgr/evogym/requires_screen": ALL,
        "tests/sgr/test_sgr_package.py": ("test_importing_sgr_evogym_leaves_evolve_alone",),
        "tests/test_first_hour.py": ("test_evolve_a_task_then_use_the_champion_as_the_readme_says",
                                     "test_the_tasks_walkthrough_evolves_a_task_of_ones_own_with_two_workers"),
        "tests/test_packaging.py": ("test_a_plain_install_runs_sgr_evolve_from_another_folder",),
        "tests/test_readme.py": ALL,
        "tests/tsim/test_precision.py": ("test_f32_steps_in_float32_and_follows_evogym_at_the_start",
                                         "test_f32_pairs_keep_the_increments_a_float32_coordinate_loses",
                                         "test_f32_state_written_from_outside_drops_stale_low_parts",
                                         "test_f32_bodies_flush_against_walls_start_as_evogyms"),
        "tests/tsim/test_runtime.py": ALL,
        "tests/tsim/test_spirv.py": (
            "test_in_f32_a_world_that_stops_mid_step_is_left_where_one_launch_leaves_it_low_parts_too",),
    },
    "ray": {
        "tests/evolve/rollout/test_ray_cluster.py": ALL,
        "tests/evolve/rollout/test_user_task.py": ("test_a_user_task_on_ray_actors",),
        "tests/evolve/runs/test_ray_nodes.py": ALL,
    },
    "browser": {
        "tests/evolve/runs/test_report_html.py": ALL,
    },
    # in-process tests of several seconds each (measured with --durations on 2 shared cores)
    "slow": {
        "tests/evolve/methods/test_baselines.py": ALL,
        "tests/evolve/runs/test_checkpoint.py": (
            "test_old_pickled_checkpoints_load_only_once_converted_with_trust_and_resume_exactly",),
        "tests/evolve/runs/test_diversity.py": ("test_every_method_with_bodies_records_it",),
        "tests/evolve/runs/test_every_task.py": ALL,
        "tests/evolve/runs/test_reporters.py": (
            "test_sgr_evolve_tensorboard_flag_writes_the_events_and_without_the_extra_says_how_to_install",),
        "tests/evolve/runs/test_explained_champion.py": (
            "test_the_end_of_run_lines_say_what_chose_the_champion_and_why",
            "test_the_headline_fitness_comes_from_episodes_that_did_not_choose",
            "test_champion_gif_shows_the_median_replay_and_the_exact_episode_is_one_flag_away",
            "test_an_auto_sized_run_killed_while_choosing_resumes_to_the_same_champion"),
        "tests/evolve/runs/test_experiment.py": ("test_killed_run_resumes_with_identical_fitness_columns",
                                                 "test_a_run_directory_is_not_overwritten",
                                                 "test_evolve_task_and_method_run_the_packaged_config_in_a"
                                                 "_named_folder"),
        "tests/evolve/runs/test_report_groups.py": (
            "test_sgr_plot_runs_star_works_after_plot_report_and_decode_wrote_there",),
        "tests/evolve/runs/test_resume.py": (
            "test_a_finished_run_is_extended_exactly_by_resume_with_more_generations",
            "test_a_full_disk_stops_the_run_with_one_line_and_it_resumes_exactly"),
        "tests/sgr/evogym/test_baseline_envs_port.py": ("test_env_creatable_and_has_correct_api",),
        "tests/sgr/evogym/test_envs.py": ("test_gym_make_of_a_bare_id_earns_evogyms_rewards",),
        "tests/sgr/evogym/test_sim.py": ("test_every_point_follows_evogym_for_300_steps",),
        "tests/tasks/test_env_rules.py": ("test_mixed_batch_equals_one_env_per_body",),
        "tests/tasks/test_evogym32.py": ("test_reset_observation_and_returns_match_evogym",
                                         "test_every_robot_return_and_com_within_evogyms_own_spread"),
        "tests/tasks/test_validation_precision.py": ALL,
        "tests/tasks/test_validation_returns.py": ALL,
        "tests/tasks/test_validation_traces.py": ALL,
        "tests/tsim/test_kernels.py": ALL,
        "tests/tsim/test_launch.py": ("test_cached_launch_follows_replaced_arrays_and_changed_arguments",),
    },
}
STARTS_PROGRAMS = ("subprocess", "ray", "browser", "vulkan")


def marks_of(path: str, name: str) -> set[str]:
    """The markers MARKS gives test `name` of the file `path` (relative to the repository), `slow`
    added to those that start programs."""
    found = {mark for mark, files in MARKS.items() for where, names in files.items()
             if (path == where or path.startswith(where + "/")) and (not names or name in names)}
    return found | ({"slow"} if found & set(STARTS_PROGRAMS) else set())


def xdist_group(rel: str, marks: set[str]) -> str:
    """The group of tests one pytest-xdist worker runs in order (`--dist loadgroup`, pyproject's
    addopts): a test file's tests together (they share module fixtures and some run in order),
    and every test that starts Ray in one group, since stopping a Ray instance stops the
    machine's others (a test's actors died beside another file's in a two-worker trial)."""
    return "ray" if "ray" in marks else rel


def pytest_collection_modifyitems(config, items) -> None:
    """Apply MARKS (a file's own `pytest.mark.slow` etc. count as well), and each test's xdist
    group."""
    root = Path(__file__).resolve().parents[1]
    for item in items:
        rel = Path(str(item.path)).resolve().relative_to(root).as_posix()
        marks = marks_of(rel, item.originalname)
        for mark in sorted(marks):
            item.add_marker(getattr(pytest.mark, mark))
        if any(item.get_closest_marker(m) for m in STARTS_PROGRAMS) and not item.get_closest_marker("slow"):
            item.add_marker(pytest.mark.slow)
        if item.get_closest_marker("ray"):
            marks.add("ray")
        item.add_marker(pytest.mark.xdist_group(xdist_group(rel, marks)))
