import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.urls import check_http_url


def test_good_urls_are_normalised() -> None:
    assert check_http_url(" http://127.0.0.1:8000/v1/ ", "base URL", "x") == "http://127.0.0.1:8000/v1"
    assert check_http_url("https://en.wikipedia.org/w/api.php?x=1", "API", "x") == (
        "https://en.wikipedia.org/w/api.php?x=1"
    )


@pytest.mark.parametrize(
    "url", ["localhost:8000", "ftp://host/", "http://", "http://h:99999/", "http://h:abc/"]
)
def test_bad_urls(url: str) -> None:
    with pytest.raises(ConfigError, match="malformed base URL") as info:
        check_http_url(url, "base URL", "http://127.0.0.1:8000/v1")
    assert "http://127.0.0.1:8000/v1" in str(info.value)


def test_query_can_be_refused() -> None:
    with pytest.raises(ConfigError, match="malformed ConceptNet API base URL"):
        check_http_url("https://api.conceptnet.io?x=1", "ConceptNet API base URL", "x", allow_query=False)
