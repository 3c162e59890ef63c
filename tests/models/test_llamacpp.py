"""Real embedded model (SmolLM2-135M through llama.cpp): chat, n, JSON schema, scoring."""

import json
from pathlib import Path

import numpy as np
import pytest

from conceptbot.core.errors import BackendRequestError, ModelCorruptError
from conceptbot.models.llamacpp import LlamaCppLLM
from conceptbot.models.llm import ChatRequest, Message, ScoreRequest
from conceptbot.models.structured import chat_json

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def llm(smollm2_path: Path) -> LlamaCppLLM:
    return LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024)


def test_greedy_chat_is_deterministic_and_counts_tokens(llm: LlamaCppLLM) -> None:
    request = ChatRequest.of("Name one fruit.", max_tokens=12)
    first, second = llm.chat(request), llm.chat(request)
    assert first.text and first.text == second.text
    assert first.usage.prompt_tokens > 5 and 0 < first.usage.completion_tokens <= 12


def test_n_completions_use_distinct_seeds(llm: LlamaCppLLM) -> None:
    response = llm.chat(ChatRequest.of("Write a random word.", n=4, temperature=1.5, max_tokens=8, seed=1))
    assert len(response.choices) == 4
    assert len(set(response.choices)) > 1
    assert response.usage.calls == 4


def test_json_schema_constrains_the_output(llm: LlamaCppLLM) -> None:
    schema = {
        "type": "object",
        "properties": {
            "object": {"type": "string"},
            "dangerous": {"type": "integer", "enum": [1, 2, 3, 4, 5]},
        },
        "required": ["object", "dangerous"],
    }
    value, _ = chat_json(llm, ChatRequest.of("Rate how dangerous a knife is, 1 to 5.", max_tokens=60), schema)
    assert value["dangerous"] in {1, 2, 3, 4, 5} and isinstance(value["object"], str)


def _reference_logprob(llm: LlamaCppLLM, prompt: str, option: str) -> float:
    """Evaluate the prompt from scratch, then the option, and sum the option's token log-probabilities.

    (The option is evaluated as its own batch, as the backend does, without its last token:
    llama.cpp's kernels for different batch shapes differ in the last digits, which shows on
    unlikely tokens of a tiny model.)
    """
    llama = llm._load()
    prompt_tokens = llama.tokenize(prompt.encode(), add_bos=True, special=True)
    option_tokens = llama.tokenize(option.encode(), add_bos=False, special=False)
    llama.reset()
    llama.eval(prompt_tokens)
    if len(option_tokens) > 1:
        llama.eval(option_tokens[:-1])  # the last token's own logits are not needed
    total = 0.0
    for j, token in enumerate(option_tokens):
        row = np.asarray(llama.scores[len(prompt_tokens) + j - 1], dtype=np.float64)
        total += row[token] - (np.log(np.sum(np.exp(row - row.max()))) + row.max())
    return total


def test_scoring_matches_a_from_scratch_evaluation(llm: LlamaCppLLM) -> None:
    prompt = "The robot should put the apple in the"
    options = (" bowl", " bowl of fruit", " blue box", " microwave oven")
    scored = llm.score(ScoreRequest(options=options, prompt=prompt))
    reference = [_reference_logprob(llm, prompt, o) for o in options]
    assert scored.logprobs == pytest.approx(reference, abs=2e-3)
    assert scored.token_counts[0] < scored.token_counts[1]
    # Order of options and a dirty KV cache (chat in between) must not change the numbers.
    llm.chat(ChatRequest.of("Say hi.", max_tokens=4))
    reversed_scores = llm.score(ScoreRequest(options=options[::-1], prompt=prompt))
    assert reversed_scores.logprobs[::-1] == pytest.approx(scored.logprobs, abs=2e-3)


def test_chat_scoring_prefers_the_greedy_reply(llm: LlamaCppLLM) -> None:
    messages = (Message("user", "What colour is the sky on a clear day? Answer in one word."),)
    greedy = llm.chat(ChatRequest(messages=messages, max_tokens=3)).text
    options = (greedy, "Purple zebra 7", "qqq xyz")
    scored = llm.score(ScoreRequest(options=options, messages=messages))
    assert int(np.argmax(scored.logprobs)) == 0


def test_scoring_after_a_chat_on_the_same_messages_matches_a_fresh_context(llm: LlamaCppLLM) -> None:
    # Chat evaluates the shared prefix without keeping its logits; scoring must not read them.
    messages = (
        Message("system", "You sort things into bins."),
        Message("user", "Where does a banana peel go?"),
    )
    options = (" compost", " glass bin", " paper bin")
    llm._load().reset()
    fresh = llm.score(ScoreRequest(options=options, messages=messages))
    llm.chat(ChatRequest(messages=messages, max_tokens=6))
    after_chat = llm.score(ScoreRequest(options=options, messages=messages))
    assert after_chat.logprobs == pytest.approx(fresh.logprobs, abs=2e-3)


def _resident_anonymous_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("RssAnon:"):
            return int(line.split()[1]) / 1024
    pytest.skip("no /proc/self/status")


def test_chat_keeps_logits_for_the_last_token_only(smollm2_path: Path) -> None:
    # Keeping a logits row per prompt token costs 2 x 4 bytes x 49,152 (SmolLM2's vocabulary) =
    # 0.4 MB per token: over 120 MB for this prompt. Nothing reads them after a chat.
    fresh = LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024)
    fresh.chat(ChatRequest.of("Hi.", max_tokens=2))  # load and allocate the compute buffers
    before = _resident_anonymous_mb()
    response = fresh.chat(ChatRequest.of("Describe a kitchen. " * 70, max_tokens=2))
    assert response.usage.prompt_tokens > 300
    assert _resident_anonymous_mb() - before < 30


def test_over_long_prompt_is_a_clear_error(llm: LlamaCppLLM) -> None:
    with pytest.raises(BackendRequestError, match="context window"):
        llm.score(ScoreRequest(options=("x",), prompt="word " * 2000))


def test_a_file_that_is_not_a_model_is_reported_corrupt(tmp_path: Path) -> None:
    bad = tmp_path / "bad.gguf"
    bad.write_bytes(b"not a gguf file" * 100)
    with pytest.raises(ModelCorruptError, match="could not load"):
        LlamaCppLLM(bad).chat(ChatRequest.of("hi"))


def test_json_in_request_round_trips() -> None:
    request = ChatRequest.of("q", json_schema={"type": "object"})
    assert json.loads(request.json_schema or "") == {"type": "object"}


def test_scoring_computes_no_logits_rows_for_the_prompt_before_its_last_token(smollm2_path: Path) -> None:
    # Only the last prompt token's row and the options' are read; a row per prompt token is a
    # vocabulary-wide product and a copy each (0.2 MB per token here).
    fresh = LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024)
    fresh.score(ScoreRequest(options=(" a", " b"), prompt="Hi."))  # load, allocate the buffers
    before = _resident_anonymous_mb()
    scored = fresh.score(ScoreRequest(options=(" yes", " no"), prompt="Describe a kitchen. " * 70))
    assert _resident_anonymous_mb() - before < 30
    reference = [_reference_logprob(fresh, "Describe a kitchen. " * 70, o) for o in (" yes", " no")]
    assert scored.logprobs == pytest.approx(reference, abs=2e-3)


def test_a_chat_after_other_questions_evaluates_only_what_its_kept_prefix_lacks(smollm2_path: Path) -> None:
    # The restating prompt's long instructions come back after the planner's other questions
    # replaced them in the context: the kept state is put back, the reply is the same.
    system = "You restate what a person asks a household robot, plainly. " * 20
    first = ChatRequest(
        messages=(Message("system", system), Message("user", "Hand me the cup.")), max_tokens=8
    )
    second = ChatRequest(messages=(Message("system", system), Message("user", "I'm cold.")), max_tokens=8)
    fresh = LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024).chat(second).text
    llm = LlamaCppLLM(smollm2_path, model="smollm2-135m", n_ctx=1024)
    llm.chat(first)
    llm.score(ScoreRequest(options=(" yes", " no"), prompt="Is the sky blue? Answer:"))
    llama = llm._load()
    evaluated: list[int] = []
    real = llama.eval
    llama.eval = lambda tokens: (evaluated.append(len(tokens)), real(tokens))[1]
    reply = llm.chat(second)
    assert reply.text == fresh
    assert reply.usage.prompt_tokens > 200 and sum(evaluated) < 40
