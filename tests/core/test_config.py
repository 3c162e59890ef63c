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
