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


@pytest.mark.parametrize(
    ("content", "fragment"),
    [
        (
            'compatible_api_key = ["sk-secret-abc"]',
            "compatible_api_key must be a non-empty string, got an array",
        ),
        ('openai_api_key = {k = "sk-secret-abc"}', "openai_api_key must be a non-empty string, got a table"),
        ("compatible_api_key = 7531902468", "compatible_api_key must be a non-empty string, got a number"),
        ('compatible_api_key = "   "', "compatible_api_key must be a non-empty string, got an empty string"),
        (
            'llm = ["openai-compatible:http://u:sk-secret-abc@h/v1#m"]',
            "llm must be a non-empty string, got an array",
        ),
        ('kg_fallback = "http://u:sk-secret-abc@h/?t=sk-secret-abc"', "got 'http://h/?t=***'"),
    ],
)
def test_type_errors_never_quote_a_secret(isolated_home: Path, content: str, fragment: str) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text(content + "\n")
    with pytest.raises(ConfigError, match=r"config\.toml") as info:
        load_settings()
    text = str(info.value)
    assert fragment in text
    assert "secret" not in text and "7531902468" not in text


def test_a_key_with_a_line_break_in_the_config_file_names_the_key_not_its_value(isolated_home: Path) -> None:
    isolated_home.mkdir(parents=True)
    (isolated_home / "config.toml").write_text('compatible_api_key = "ck-abc\\nX-Evil: 1"\n')
    with pytest.raises(ConfigError) as info:
        load_settings()
    text = str(info.value)
    assert "config.toml: compatible_api_key holds a line break" in text and "ck-abc" not in text
    assert info.value.hint and "printable ASCII" in info.value.hint


def test_a_key_with_surrounding_whitespace_is_accepted_stripped(isolated_home: Path) -> None:
    env = {"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_API_KEY": " ck-456\n"}  # $(cat keyfile)
    assert load_settings(env=env).compatible_api_key == "ck-456"


@pytest.mark.parametrize("value", ["1000000000", "131073"])
def test_an_absurd_context_size_is_refused_when_settings_are_read(isolated_home: Path, value: str) -> None:
    with pytest.raises(ConfigError) as info:
        load_settings(env={"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_N_CTX": value})
    assert "CONCEPTBOT_N_CTX: n_ctx must be at most 131072 tokens" in str(info.value)
    assert info.value.hint and "32768" in info.value.hint


def test_the_largest_context_size_is_accepted(isolated_home: Path) -> None:
    env = {"CONCEPTBOT_HOME": str(isolated_home), "CONCEPTBOT_N_CTX": "131072"}
    assert load_settings(env=env).n_ctx == 131072
