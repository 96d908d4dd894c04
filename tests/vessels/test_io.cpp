// Readers and writers on files the tests write themselves (filled in below).
#include <gtest/gtest.h>
