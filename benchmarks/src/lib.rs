//! Speed comparisons and scaling studies (issue 9). (Being written.)
