from pathlib import Path

import pytest

from conceptbot.core.config import DEFAULT_LLM, load_settings
from conceptbot.core.errors import ConfigError


def test_defaults_live_under_the_home(isolated_home: Path) -> None:
    settings = load_settings()
    assert settings.home == isolated_home
    assert settings.llm == DEFAULT_LLM
    assert settings.models_dir == isolated_home / "models"
    assert settings.cache_db == isolated_home / "cache.db"


def test_precedence_file_then_env_then_overrides(isolated_home: Path) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text('llm = "openai:gpt-4o-mini"\ntimeout_s = 5\nmax_retries = 1\n')
    env = {"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_MAX_RETRIES": "2"}
    settings = load_settings(env=env)
    assert (settings.llm, settings.timeout_s, settings.max_retries) == ("openai:gpt-4o-mini", 5, 2)
    assert load_settings(env=env, llm="fake").llm == "fake"


def test_secrets_stay_out_of_repr(isolated_home: Path) -> None:
    settings = load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), "OPENAI_API_KEY": "sk-secret-123"})
    assert settings.openai_api_key == "sk-secret-123"
    assert "sk-secret" not in repr(settings)


@pytest.mark.parametrize(
    ("content", "fragment"),
    [("llm = ", "not valid TOML"), ('colour = "red"', "unknown setting 'colour'")],
)
def test_bad_config_file_is_a_clear_error(isolated_home: Path, content: str, fragment: str) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text(content)
    with pytest.raises(ConfigError, match=fragment):
        load_settings()


def test_bad_number_in_environment(isolated_home: Path) -> None:
    with pytest.raises(ConfigError, match="CONCEPTBOT_TIMEOUT"):
        load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_TIMEOUT": "soon"})


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        ('n_ctx = "abc"', "n_ctx must be a whole number, got 'abc'"),
        ('timeout_s = "abc"', "timeout_s must be a number, got 'abc'"),
        ("timeout_s = -1", "timeout_s must be a number of seconds >= 0.1"),
        ("n_ctx = 100", "n_ctx must be a whole number of tokens >= 512"),
        ("n_ctx = 4096.5", "n_ctx must be an int"),
        ("max_retries = true", "max_retries must be an int"),
        ("llm = 3", "llm must be a non-empty string"),
        ('use_cache = "maybe"', "use_cache must be 1/0 or true/false"),
    ],
)
def test_wrong_value_types_in_the_config_file_name_the_setting(
    isolated_home: Path, content: str, fragment: str
) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text(content)
    with pytest.raises(ConfigError, match=r"config\.toml") as info:
        load_settings()
    assert fragment in str(info.value)


def test_config_file_that_is_not_utf8(isolated_home: Path) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_bytes(b'llm = "caf\xe9"\n\xff\xfe')
    with pytest.raises(ConfigError, match="is not UTF-8 text"):
        load_settings()


@pytest.mark.parametrize(
    ("var", "value", "fragment"),
    [
        ("CONCEPTBOT_TIMEOUT", "-1", "CONCEPTBOT_TIMEOUT: timeout_s must be a number of seconds >= 0.1"),
        ("CONCEPTBOT_TIMEOUT", "nan", "timeout_s must be a finite number"),
        ("CONCEPTBOT_N_CTX", "-5", "CONCEPTBOT_N_CTX: n_ctx must be a whole number of tokens >= 512"),
        ("CONCEPTBOT_THREADS", "0", "CONCEPTBOT_THREADS: n_threads must be a whole number >= 1"),
        ("CONCEPTBOT_MAX_RETRIES", "-2", "max_retries must be a whole number >= 0"),
    ],
)
def test_out_of_range_environment_values_are_named(
    isolated_home: Path, var: str, value: str, fragment: str
) -> None:
    with pytest.raises(ConfigError) as info:
        load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), var: value})
    assert fragment in str(info.value)


def test_valid_values_are_coerced(isolated_home: Path) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text("timeout_s = 5\nn_ctx = 2048\nkg_fallback = false\n")
    settings = load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_THREADS": "2"})
    assert (settings.timeout_s, settings.n_ctx, settings.kg_fallback, settings.n_threads) == (
        5.0,
        2048,
        False,
        2,
    )
    assert isinstance(settings.timeout_s, float)
