// "did you mean ...?" for misspelt names (env ids, cameras, overlays, commands) and the comma
// lists they come in.
#pragma once

#include <string>
#include <vector>

namespace fetchscope {

/// Edit distance between `a` and `b`, ignoring ASCII case: insertions, deletions,
/// substitutions and swaps of two neighbouring characters each cost 1 (optimal string alignment).
int EditDistance(const std::string& a, const std::string& b);

/// The candidate nearest to `word` when it is near enough to be a slip: at most 1 edit for short
/// words, up to a third of the word's length for longer ones (ties: the first listed). Empty
/// when nothing is that near.
std::string ClosestName(const std::string& word, const std::vector<std::string>& candidates);

/// " (did you mean 'X'?)" for ClosestName's answer, or "" when there is none: to append to an
/// error message.
std::string DidYouMean(const std::string& word, const std::vector<std::string>& candidates);

/// Splits a comma list and trims spaces and tabs around each item, so "goal, hud" gives "goal"
/// and "hud". Empty items are kept (empty strings), for the caller to reject.
std::vector<std::string> SplitCommaList(const std::string& text);

/// `text` without leading and trailing spaces and tabs.
std::string TrimSpaces(const std::string& text);

}  // namespace fetchscope
