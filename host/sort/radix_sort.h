#pragma once
// Placeholder: the radix sort (issue 4) lives here.
