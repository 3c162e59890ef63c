import pytest

from conceptbot.core.errors import ConfigError
from conceptbot.core.urls import Redactor, check_http_url, redact_secrets, split_query, url_secrets


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


def test_a_redactor_masks_configured_secrets_whatever_surrounds_them() -> None:
    redact = Redactor(keys=("ck-456",), urls=("http://alice:hunter2pw@h/v1?tenant=Q-77x&v=1",))
    text = "key ck-456; token:ck-456 (Basic YWxpY2U6aHVudGVyMnB3) pw hunter2pw, tenant Q-77x v 1"
    assert redact(text) == "key ***; token:*** (Basic ***) pw ***, tenant *** v 1"
    assert "ck-456" not in repr(redact) and "hunter2pw" not in repr(redact)


def test_a_redactor_masks_percent_encoded_and_decoded_forms() -> None:
    redact = Redactor(keys=("a/b+c=d",), urls=("http://u:p%40ss-word@h/v1?k=s%20ecret",))
    assert redact("a/b+c=d a%2Fb%2Bc%3Dd p@ss-word p%40ss-word s ecret") == "*** *** *** *** ***"


def test_short_values_are_left_to_the_patterns() -> None:
    # Masking "1" or "v2" by value would garble every message; such a value protects nothing.
    redact = Redactor(keys=("abc",), urls=("http://h/v1?v=1",))
    assert redact("HTTP 500 abc v=1 key=1") == "HTTP 500 abc v=1 key=***"


def test_url_secrets_lists_password_basic_form_and_query_values() -> None:
    found = url_secrets("https://bob:pw-9999@h/v1?key=KEY-1234&FLAG")
    assert {"pw-9999", "Ym9iOnB3LTk5OTk=", "Ym9iOnB3LTk5OTk", "KEY-1234", "FLAG"} <= set(found)
    assert url_secrets("http://h/v1") == [] and url_secrets(None) == []


def test_basic_credentials_in_free_text_are_masked_but_not_english() -> None:
    assert redact_secrets("Authorization: Basic YWxpY2U6aHVudGVyMnB3") == "Authorization: Basic ***"
    assert redact_secrets("use Basic authentication") == "use Basic authentication"


def test_split_query_keeps_the_path_and_decodes_values() -> None:
    assert split_query("http://u:p@h:8/ok/v1/?api_key=X%2BY&v=&FLAG#m") == (
        "http://u:p@h:8/ok/v1",
        {"api_key": "X+Y", "v": "", "FLAG": ""},
    )
    assert split_query("http://h/v1") == ("http://h/v1", {})
